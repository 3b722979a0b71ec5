"""Console benchmark: the Textual console polling 100 watched variables flat out.

    python benchmarks/console_bench.py [--seconds 3] [--rounds 5] [--frames 200000]
                                       [--port PORT] [--json FILE]

The console (``RacConsoleApp``, headless, 120x40, the frame log visible) runs an engine
at interval 0 watching I 0-99 against a responder (the C one, built with ``cc -O2``,
unless ``--port`` names another; the Python one, with a warning, when there is no
compiler), the clients and the responder on one CPU unless ``--placement`` says otherwise
(see ``run.py``). In one run, alternating over ROUNDS so that machine noise mostly cancels:

  - the session client alone (``Session.get`` in a loop, its own process, no UI);
  - the console's poll rate (poll requests sent, counted in the batches the console
    drains) and its ratio to the session client (target >= 0.8), with the console
    process's CPU per poll and per 1000 frames;
  - key to screen while polling: a key posted to the app every 100 ms, timed until
    the first screen update after the command line holds it (median, p95; target
    p95 <= 50 ms);
  - process memory at start, after 10k frames and after FRAMES frames (the log is
    bounded, so it should stay flat).

Each console round is a process of its own (``--child``), as the console is; it prints
one JSON line. ``run.py`` runs the same rounds beside its other sides.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import resource
import statistics
import tempfile
import time
from pathlib import Path

from bench_common import (
    CPrograms,
    Run,
    child,
    child_run,
    placement_cpus,
    start_responder,
)

KEY_EVERY = 0.1
KEY_TIMEOUT = 2.0


def rss_mb() -> float:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def cpu_now() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


async def measure_console(
    port: int,
    seconds: float,
    warmup: float,
    soak_frames: int,
    watch: tuple[str, ...] = ("watch I 0-99",),
    press: tuple[str, ...] = (),
    csv: str | None = None,
) -> dict:
    """In this process: the console against 127.0.0.1:PORT, watching what ``watch``
    says, after pressing ``press`` (F5: the I/O grid), logging to ``csv`` when given;
    the figures as a dict."""
    from textual import events

    from rac_console.engine import Engine, Outbox
    from rac_console.present.history import History
    from rac_console.session import Frame
    from rac_console.tui.app import RacConsoleApp

    class CountingOutbox(Outbox):
        """The engine's outbox, counting what the console drains: poll requests and
        frames, with the time and this process's CPU at each drain."""

        def __init__(self) -> None:
            super().__init__()
            self.polls = self.frames = 0
            self.mark = (time.perf_counter(), 0, 0, cpu_now())

        def drain(self):  # type: ignore[no-untyped-def]
            batch = super().drain()
            polls = frames = 0
            for event in batch.events:
                if type(event) is Frame:
                    frames += 1
                    if event.poll and event.direction == "tx":
                        polls += 1
            self.polls += polls
            self.frames += frames
            self.mark = (time.perf_counter(), self.polls, self.frames, cpu_now())
            return batch

    outbox = CountingOutbox()
    engine = Engine(
        "127.0.0.1", port, timeout=2.0, interval=0.0, outbox=outbox, cycles=True, log_csv=csv
    )
    out: dict = {}
    with tempfile.TemporaryDirectory() as home:
        app = RacConsoleApp(engine, History(Path(home) / "history"))
        async with app.run_test(size=(120, 40)) as pilot:
            await pilot.pause(0.3)
            out["memory_start_mb"] = rss_mb()
            command_line = app.main_screen.panes.command_line
            for line in watch:
                command_line.insert_text_at_cursor(line)
                await pilot.press("enter")
            if press:
                await pilot.press(*press)
                command_line.focus()
            started = time.perf_counter()
            while outbox.polls == 0 or time.perf_counter() - started < warmup:
                await asyncio.sleep(0.05)

            # Key to screen: a key goes through the app's queue as a typed key does; it
            # is on screen at the first display after the command line holds it.
            latencies: list[float] = []
            shown = asyncio.Event()
            pending: list[tuple[str, float]] = []
            hook = app.post_display_hook

            def displayed() -> None:
                hook()
                if pending and command_line.value == pending[0][0]:
                    latencies.append((time.perf_counter() - pending.pop()[1]) * 1000)
                    shown.set()

            app.post_display_hook = displayed  # type: ignore[method-assign]
            if seconds > 0:
                first = outbox.mark
                end = time.perf_counter() + seconds
                while time.perf_counter() < end:
                    command_line.value = ""
                    await asyncio.sleep(KEY_EVERY)
                    shown.clear()
                    pending[:] = [(command_line.value + "x", time.perf_counter())]
                    app.post_message(events.Key("x", "x"))
                    try:
                        await asyncio.wait_for(shown.wait(), KEY_TIMEOUT)
                    except TimeoutError:
                        pending.clear()
                        latencies.append(KEY_TIMEOUT * 1000)
                await asyncio.sleep(1.5 / 20)  # one more drain, at least
                last = outbox.mark
                out |= {
                    "requests": last[1] - first[1],
                    "seconds": last[0] - first[0],
                    "cpu": last[3] - first[3],
                    "frames": last[2] - first[2],
                    "key_ms": latencies,
                }
            command_line.value = ""
            out["memory_polling_mb"] = rss_mb()
            if soak_frames:
                memory_10k = None
                while outbox.frames < soak_frames:
                    if memory_10k is None and outbox.frames >= 10_000:
                        memory_10k = rss_mb()
                    await asyncio.sleep(0.2)
                out["memory_10k_frames_mb"] = memory_10k or out["memory_polling_mb"]
                out["memory_after_mb"] = rss_mb()
                out["soak_frames"] = outbox.frames
    return out


def console_round(
    port: int,
    seconds: float,
    warmup: float,
    cpu: int | None = None,
    watch: tuple[str, ...] = (),
    press: tuple[str, ...] = (),
    csv: str | None = None,
) -> tuple[Run, dict]:
    """One console round in a process of its own: its Run and all it reported."""
    more: list[object] = [f"--watch-line={line}" for line in watch]
    more += [f"--press={key}" for key in press]
    more += ["--csv", csv] if csv else []
    out = child("console_bench.py", "--child", "--port", port, "--seconds", seconds,
                "--warmup", warmup, *more, cpu=cpu)  # fmt: skip
    return Run(out["requests"], out["seconds"], out["cpu"]), out


def console_soak(port: int, frames: int, cpu: int | None = None) -> dict:
    """Memory while the console takes ``frames`` frames, in a process of its own."""
    return child(
        "console_bench.py", "--child", "--port", port, "--seconds", 0, "--soak", frames,
        timeout=1800, cpu=cpu,
    )  # fmt: skip


def key_figures(latencies: list[float]) -> dict[str, float]:
    ordered = sorted(latencies)
    return {
        "key_median_ms": statistics.median(ordered),
        "key_p95_ms": ordered[max(0, int(len(ordered) * 0.95 + 0.5) - 1)],
        "key_samples": float(len(ordered)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="length of each round")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=200_000, help="frames for memory")
    parser.add_argument("--port", type=int, help="a responder already listening")
    parser.add_argument(
        "--placement",
        choices=("same", "apart", "free"),
        default="same",
        help="CPUs of the clients and the responder (see run.py); default same",
    )
    parser.add_argument("--json", metavar="FILE")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--warmup", type=float, default=1.0, help=argparse.SUPPRESS)
    parser.add_argument("--soak", type=int, default=0, help=argparse.SUPPRESS)
    parser.add_argument("--watch-line", action="append", default=[], help=argparse.SUPPRESS)
    parser.add_argument("--press", action="append", default=[], help=argparse.SUPPRESS)
    parser.add_argument("--csv", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        watch = tuple(args.watch_line) or ("watch I 0-99",)
        out = asyncio.run(
            measure_console(
                args.port, args.seconds, args.warmup, args.soak, watch, tuple(args.press), args.csv
            )
        )
        print(json.dumps(out), flush=True)
        return
    programs = CPrograms()
    server = None
    try:
        client_cpu, server_cpu = placement_cpus(args.placement)
        port = args.port
        if port is None:
            server, what = start_responder(programs, server_cpu)
            port = server.port
            print(f"against the {what} on 127.0.0.1:{port}")
        session: list[Run] = []
        console: list[Run] = []
        latencies: list[float] = []
        for n in range(args.rounds):
            sides = ["session", "console"] if n % 2 == 0 else ["console", "session"]
            for side in sides:
                if side == "session":
                    session.append(
                        child_run("bench_clients.py", "session", port, args.seconds, cpu=client_cpu)
                    )
                else:
                    run, out = console_round(port, args.seconds, 1.0, client_cpu)
                    console.append(run)
                    latencies += out["key_ms"]
        soak = console_soak(port, args.frames, client_cpu)
    finally:
        if server is not None:
            server.stop()
        programs.cleanup()
    ratios = sorted(c.rate / s.rate for c, s in zip(console, session, strict=True))
    results = {
        "session_rps": statistics.median(r.rate for r in session),
        "session_cpu_us": statistics.median(r.cpu_us for r in session),
        "console_polls_per_s": statistics.median(r.rate for r in console),
        "console_cpu_us": statistics.median(r.cpu_us for r in console),
        "console_to_session_ratio": statistics.median(ratios),
        **key_figures(latencies),
        **{k: v for k, v in soak.items() if k.startswith("memory")},
        "soak_frames": soak["soak_frames"],
    }
    rows = [
        ("session client GETs/s (no UI)", f"{results['session_rps']:,.0f}",
         f"{results['session_cpu_us']:.1f} µs CPU/req"),
        ("console polls/s (100 watched, log visible)", f"{results['console_polls_per_s']:,.0f}",
         f"{results['console_cpu_us']:.1f} µs CPU/poll"),
        ("console / session (median of rounds)", f"{results['console_to_session_ratio']:.2f}",
         f">= 0.80  (rounds {ratios[0]:.2f}..{ratios[-1]:.2f})"),
        ("key to screen, median ms", f"{results['key_median_ms']:.1f}", ""),
        ("key to screen, p95 ms", f"{results['key_p95_ms']:.1f}", "<= 50"),
        ("memory at start, MB", f"{results['memory_start_mb']:.0f}", ""),
        ("memory after 10k frames, MB", f"{results['memory_10k_frames_mb']:.0f}", ""),
        (f"memory after {soak['soak_frames']:,} frames, MB",
         f"{results['memory_after_mb']:.0f}", "flat"),
    ]  # fmt: skip
    width = max(len(r[0]) for r in rows)
    print(f"{'measure':<{width}}  {'value':>10}  target / CPU")
    for name, value, target in rows:
        print(f"{name:<{width}}  {value:>10}  {target}")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
