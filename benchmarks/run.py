"""The benchmark suite: every client path measured side by side against a C responder.

    python benchmarks/run.py [--json results.json]     # the full run (a few minutes)
    python benchmarks/run.py --smoke                    # tiny sizes, as CI runs it

Against ``benchmarks/c/rac_responder.c`` (built with ``cc -O2`` into a temp dir; without
a compiler the Python responder stands in, with a loud warning), one request in flight:

  1. the C load client, 1 session: the floor;
  2. a bare blocking-socket Python loop (sendall, recv, split on CR);
  3. the session client, ``Session.get(kind_of("I"), 10)`` in a loop: >= 0.8x the bare loop;
  4. watch polling through the engine: interval 0, I 0-99 watched, drained every 50 ms
     as a front end does; rate = poll requests sent: >= 0.9x the session client;
  5. the Textual console (headless) polling the same 100 variables flat out: >= 0.8x
     the session client, key to screen p95 <= 50 ms (see ``console_bench.py``);

then 6. the simulator (``rac-console sim``) over 50 sessions against the C responder
over 50 sessions, the C load client driving both: >= 0.5x.

Every side runs in a process of its own, as a controller and a console would; each
round runs every side once, in turn (the order reversed every other round), and a
ratio is the median of the per-round ratios, so noise on a shared machine mostly
cancels.

Sides 1-5 run with the client and the responder on one CPU (``--placement same``): with
one request in flight a request then costs the client's CPU, the responder's and two
context switches, so the rates compare what each client path costs. On this project's
machine (a 2-vCPU VM) a wake-up across CPUs costs hundreds of µs whenever the other vCPU
is idle: the C client made 45,000 requests/s on one CPU and 2,500-4,500 across two, so
``apart`` and ``free`` measure mostly the hypervisor. The 50-session runs keep every
CPU busy and run ``free``.

Beside every rate is its CPU per request: the measuring client process's user + system
time over its measured window (rows 1-5; the engine and the console: every thread, per
poll), the server's (the 50-session rows). The session client is also run once under
cProfile (in its own process, same placement) and its top entries printed.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import pstats
import pty
import select
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_common import (  # noqa: E402
    CPrograms,
    Run,
    Server,
    alternate,
    child_run,
    median_cpu_us,
    median_rate,
    placement_cpus,
    proc_cpu,
    ratio,
    run_c_client,
    start_responder,
    warn,
)
from console_bench import console_round, console_soak, key_figures  # noqa: E402
from sim_harness import SimulatorProcess  # noqa: E402

SIM_SESSIONS = 50
PLACEMENTS = ("same", "apart", "free")


# ----------------------------------------------------------------- 1-5: one session


def client_sections(
    programs: CPrograms, port: int, seconds: float, rounds: int, warmup: float, cpu: int | None
) -> tuple[dict[str, float], dict[str, list[Run]]]:
    """Sides 1-5 against one responder, alternated over the rounds, each client on ``cpu``."""
    keys: list[float] = []
    per_1000_frames: list[float] = []

    def python_side(mode: str) -> Callable[[], Run]:
        return lambda: child_run("bench_clients.py", mode, port, seconds, warmup, cpu=cpu)

    def console() -> Run:
        run, out = console_round(port, seconds, max(warmup, 0.5), cpu)
        keys.extend(out["key_ms"])
        if out["frames"]:
            per_1000_frames.append(out["cpu"] / out["frames"] * 1e6)
        return run

    sides: dict[str, Callable[[], Run]] = {}
    if programs.client is not None:
        client = programs.client
        sides["c"] = lambda: run_c_client(client, port, 1, seconds, cpu)
    sides |= {
        "bare": python_side("bare"),
        "session": python_side("session"),
        "engine": python_side("engine"),
        "console": console,
    }
    runs = alternate(rounds, sides)
    out = {
        "bare_loop_rps": median_rate(runs["bare"]),
        "bare_loop_cpu_us": median_cpu_us(runs["bare"]),
        "session_rps": median_rate(runs["session"]),
        "session_cpu_us": median_cpu_us(runs["session"]),
        "session_to_bare_ratio": ratio(runs, "session", "bare"),
        "engine_polls_per_s": median_rate(runs["engine"]),
        "engine_cpu_us": median_cpu_us(runs["engine"]),
        "engine_to_session_ratio": ratio(runs, "engine", "session"),
        "console_polls_per_s": median_rate(runs["console"]),
        "console_cpu_us": median_cpu_us(runs["console"]),
        "console_to_session_ratio": ratio(runs, "console", "session"),
        "cpu_ms_per_1000_frames": statistics.median(per_1000_frames),
        **key_figures(keys),
    }
    if "c" in runs:
        out |= {
            "c_client_rps": median_rate(runs["c"]),
            "c_client_cpu_us": median_cpu_us(runs["c"]),
            "bare_to_c_ratio": ratio(runs, "bare", "c"),
            "session_to_c_ratio": ratio(runs, "session", "c"),
        }
    return out, runs


def profile_session(port: int, seconds: float, top: int, cpu: int | None) -> list[str]:
    """The session client loop under cProfile, in its own process: the top entries."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "session.prof"
        run = child_run("bench_clients.py", "profile", port, seconds, path, cpu=cpu)
        stats = pstats.Stats(str(path))
        total = stats.total_tt  # type: ignore[attr-defined]
        width = 60
        lines = [
            f"session client under cProfile: {run.requests:,.0f} GETs in {run.seconds:.1f} s "
            f"(slowed by the profiler), {total:.2f} s profiled; top {top} by own time:",
            f"  {'own s':>7} {'own %':>6} {'cum s':>7} {'calls':>9}  function",
        ]
        entries = sorted(stats.stats.items(), key=lambda item: item[1][2], reverse=True)  # type: ignore[attr-defined]
        for (file, line, name), (_cc, calls, own, cum, _callers) in entries[:top]:
            where = f"{Path(file).name}:{line}({name})" if line else name
            lines.append(
                f"  {own:>7.3f} {own / total:>6.1%} {cum:>7.3f} {calls:>9,}  {where[:width]}"
            )
        return lines


# ----------------------------------------------------------------- 6: 50 sessions


def simulator_section(
    programs: CPrograms, seconds: float, rounds: int
) -> tuple[dict[str, float], dict[str, list[Run]]]:
    """The simulator over 50 sessions against the responder over 50 sessions, the same
    load client driving both; CPU per request is the server's."""
    servers: dict[str, tuple[int, Callable[[], float]]] = {}
    stops: list[Callable[[], None]] = []
    try:
        responder, _ = start_responder(programs)
        stops.append(responder.stop)
        servers["responder"] = (responder.port, responder.cpu)
        epoll = epoll_responder(programs)
        if epoll is not None:
            stops.append(epoll.stop)
            servers["epoll"] = (epoll.port, epoll.cpu)
        sim = SimulatorProcess()
        stops.append(sim.stop)
        servers["sim"] = (sim.port, lambda: proc_cpu(sim.pid))

        def drive(port: int, cpu: Callable[[], float], length: float) -> Run:
            before = cpu()
            if programs.client is not None:
                run = run_c_client(programs.client, port, SIM_SESSIONS, length)
            else:
                run = child_run("bench_clients.py", "multi", port, length, SIM_SESSIONS)
            return Run(run.requests, run.seconds, cpu() - before)

        for port, cpu in servers.values():
            drive(port, cpu, min(0.5, seconds))  # warm-up
        sides = {
            name: (lambda port=port, cpu=cpu: drive(port, cpu, seconds))
            for name, (port, cpu) in servers.items()
        }
        runs = alternate(rounds, sides)  # type: ignore[arg-type]
    finally:
        for stop in reversed(stops):
            stop()
    out = {
        "simulator_50_sessions_rps": median_rate(runs["sim"]),
        "simulator_50_sessions_cpu_us": median_cpu_us(runs["sim"]),
        "responder_50_sessions_rps": median_rate(runs["responder"]),
        "responder_50_sessions_cpu_us": median_cpu_us(runs["responder"]),
        "simulator_to_responder_50_ratio": ratio(runs, "sim", "responder"),
    }
    if "epoll" in runs:
        out |= {
            "epoll_50_sessions_rps": median_rate(runs["epoll"]),
            "epoll_50_sessions_cpu_us": median_cpu_us(runs["epoll"]),
            "simulator_to_epoll_50_ratio": ratio(runs, "sim", "epoll"),
        }
    return out, runs


def epoll_responder(programs: CPrograms) -> Server | None:
    """``c/rac_epoll_responder.c`` (Linux), when it is there and builds; else None."""
    if programs.responder is None or not sys.platform.startswith("linux"):
        return None
    binary = programs.build_optional("rac_epoll_responder")
    return Server([str(binary), "0"]) if binary is not None else None


# ----------------------------------------------------------------- start-up


def first_paint(runs: int) -> float:
    """Process start to the first screen that names its target, in a real pty."""
    times = []
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as home:
            env = os.environ | {
                "HOME": home,
                "XDG_STATE_HOME": home,
                "TERM": "xterm-256color",
                "COLUMNS": "120",
                "LINES": "40",
            }
            master, slave = pty.openpty()
            started = time.perf_counter()
            process = subprocess.Popen(
                [sys.executable, "-m", "rac_console"],
                stdin=slave,
                stdout=slave,
                stderr=slave,
                env=env,
                close_fds=True,
            )
            os.close(slave)
            seen, painted = b"", None
            while painted is None and time.perf_counter() - started < 20:
                ready, _, _ = select.select([master], [], [], 0.5)
                if ready:
                    try:
                        seen += os.read(master, 65536)
                    except OSError:
                        break
                    if b"SIMULATOR" in seen:
                        painted = time.perf_counter() - started
            process.terminate()
            process.wait(timeout=10)
            os.close(master)
            if painted is not None:
                times.append(painted)
    return statistics.median(times) if times else float("nan")


def version_time(runs: int) -> float:
    times = []
    for _ in range(runs):
        started = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "rac_console", "--version"], check=True, capture_output=True
        )
        times.append(time.perf_counter() - started)
    return statistics.median(times)


# ------------------------------------------------------------------------ report

#: (label, rate key, CPU key, ratio key, ratio text, target text, check)
ROWS: list[tuple[str, str | None, str | None, str | None, str, str, Callable | None]] = [
    ("C client, 1 session (the floor)", "c_client_rps", "c_client_cpu_us", None, "",
     "floor", None),
    ("bare Python socket loop", "bare_loop_rps", "bare_loop_cpu_us", "bare_to_c_ratio",
     "x C", "reported", None),
    ("session client: Session.get", "session_rps", "session_cpu_us", "session_to_bare_ratio",
     "x bare", ">= 0.80x bare", lambda v: v >= 0.8),
    ("engine: watch I 0-99, interval 0", "engine_polls_per_s", "engine_cpu_us",
     "engine_to_session_ratio", "x session", ">= 0.90x session", lambda v: v >= 0.9),
    ("console: 100 watched, headless", "console_polls_per_s", "console_cpu_us",
     "console_to_session_ratio", "x session", ">= 0.80x session", lambda v: v >= 0.8),
    ("console: key to screen, p95", None, None, "key_p95_ms", "ms", "<= 50 ms",
     lambda v: v <= 50),
    ("console: key to screen, median", None, None, "key_median_ms", "ms", "reported", None),
    ("simulator, 50 sessions (server CPU)", "simulator_50_sessions_rps",
     "simulator_50_sessions_cpu_us", "simulator_to_responder_50_ratio", "x resp.",
     ">= 0.50x responder", lambda v: v >= 0.5),
    ("responder, 50 sessions (server CPU)", "responder_50_sessions_rps",
     "responder_50_sessions_cpu_us", None, "", "reference", None),
    ("C epoll responder, 50 sessions", "epoll_50_sessions_rps", "epoll_50_sessions_cpu_us",
     "simulator_to_epoll_50_ratio", "sim x", "reported", None),
    ("console: CPU per 1000 frames", None, None, "cpu_ms_per_1000_frames", "ms", "reported",
     None),
    ("console: memory after/at 10k frames", None, None, "memory_growth", "x", "<= 1.20x",
     lambda v: v <= 1.2),
    ("cold start to first paint", None, None, "first_paint_s", "s", "< 1 s",
     lambda v: v < 1),
    ("rac-console --version", None, None, "version_s", "s", "< 0.3 s", lambda v: v < 0.3),
]  # fmt: skip

#: The per-round ratios printed under the table.
SPREAD = [
    ("bare", "c"),
    ("session", "bare"),
    ("engine", "session"),
    ("console", "session"),
    ("sim_50", "responder_50"),
]

HEADER = ("path", "req/s", "µs CPU/request", "ratio", "target", "met?")


def table(results: dict[str, float]) -> list[str]:
    rows = [HEADER]
    for label, rate, cpu, ratio_key, unit, target, check in ROWS:
        if rate is not None and rate not in results:
            continue
        if rate is None and (ratio_key is None or ratio_key not in results):
            continue
        value = results.get(ratio_key) if ratio_key else None
        rows.append(
            (
                label,
                f"{results[rate]:,.0f}" if rate else "",
                f"{results[cpu]:.1f}" if cpu and cpu in results else "",
                f"{value:.2f} {unit}" if value is not None else "1.00" * (target == "floor"),
                target,
                ("met" if check(value) else "MISSED") if check and value is not None else "",
            )
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(HEADER))]
    right = (False, True, True, True, False, False)

    def line(row: tuple[str, ...]) -> str:
        cells = [
            cell.rjust(width) if r else cell.ljust(width)
            for cell, width, r in zip(row, widths, right, strict=True)
        ]
        return "| " + " | ".join(cells) + " |"

    pairs = zip(widths, right, strict=True)
    dashes = ["-" * (width + 1) + (":" if r else "-") for width, r in pairs]
    rule = "|" + "|".join(dashes) + "|"
    return [line(rows[0]), rule, *(line(row) for row in rows[1:])]


def machine() -> str:
    return (
        f"{platform.python_implementation()} {platform.python_version()}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs, {platform.system()} {platform.release()}, "
        f"load {' '.join(f'{x:.2f}' for x in os.getloadavg())}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: checks it runs")
    parser.add_argument("--seconds", type=float, default=2.0, help="length of each round")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument(
        "--frames", type=int, default=200_000, help="frames through the console for memory"
    )
    parser.add_argument("--json", metavar="FILE", help="also write every figure as JSON")
    parser.add_argument(
        "--placement",
        choices=PLACEMENTS,
        default="same",
        help="CPUs for sides 1-5: same (client and responder share one CPU: the default, "
        "see the docstring), apart (one each), free (the scheduler decides)",
    )
    args = parser.parse_args()
    warmup, paints, versions, top = 0.3, 5, 9, 20
    if args.smoke:
        args.seconds, args.rounds, args.frames = 0.3, 1, 3_000
        warmup, paints, versions, top = 0.1, 1, 1, 8
    print("$ " + shlex.join([Path(sys.executable).name, *sys.argv]))
    print(f"# {machine()}")
    started = time.monotonic()
    programs = CPrograms()
    client_cpu, server_cpu = placement_cpus(args.placement)
    meta: dict[str, object] = {
        "machine": machine(),
        "c_compiled": programs.client is not None,
        "placement": args.placement,
        "cpus": [client_cpu, server_cpu],
    }
    results: dict[str, float] = {}
    rounds: dict[str, list[dict[str, float]]] = {}
    try:
        responder, what = start_responder(programs, server_cpu)
        meta["responder"] = what
        print(
            f"# against the {what}, {args.rounds} rounds of {args.seconds:g} s per side, "
            f"one request in flight; sides 1-5 placed {args.placement} "
            f"(client CPU {client_cpu}, responder CPU {server_cpu}); 50 sessions: free"
        )
        try:
            figures, runs = client_sections(programs, responder.port, args.seconds,
                                            args.rounds, warmup, client_cpu)  # fmt: skip
            results |= figures
            rounds |= {name: [as_dict(run) for run in side] for name, side in runs.items()}
            soak = console_soak(responder.port, args.frames, client_cpu)
            results |= {k: float(v) for k, v in soak.items() if k.startswith(("memory", "soak"))}
            results["memory_growth"] = soak["memory_after_mb"] / soak["memory_10k_frames_mb"]
            profile = profile_session(responder.port, max(args.seconds, 0.5), top, client_cpu)
        finally:
            responder.stop()
        figures, runs = simulator_section(programs, args.seconds, args.rounds)
        results |= figures
        rounds |= {f"{name}_50": [as_dict(run) for run in side] for name, side in runs.items()}
    finally:
        programs.cleanup()
    results["first_paint_s"] = first_paint(paints)
    results["version_s"] = version_time(versions)
    print()
    print("\n".join(table(results)))
    print(
        "# µs CPU/request: user+system CPU of the measuring client process over its window "
        "(engine and console: every thread, per poll); 50-session rows: the server's"
    )
    for top_side, bottom_side in SPREAD:
        if top_side in rounds and bottom_side in rounds:
            each = [
                a["rate"] / b["rate"]
                for a, b in zip(rounds[top_side], rounds[bottom_side], strict=True)
            ]
            print(f"# {top_side}/{bottom_side} per round: " + " ".join(f"{r:.2f}" for r in each))
    print(f"# {time.monotonic() - started:.0f} s")
    if programs.client is None:
        warn(f"{programs.error}: no C figures; the PYTHON responder stood in")
    print()
    print("\n".join(profile))
    if args.json:
        Path(args.json).write_text(
            json.dumps({**results, "rounds": rounds, "meta": meta}, indent=2)
        )


def as_dict(run: Run) -> dict[str, float]:
    return {"rate": run.rate, "cpu_us": run.cpu_us, "seconds": run.seconds}


if __name__ == "__main__":
    main()
