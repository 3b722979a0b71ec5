"""The benchmark suite: every figure of the performance issue, measured side by side.

    python benchmarks/run.py [--json results.json]     # the full run (a few minutes)
    python benchmarks/run.py --smoke                    # tiny sizes, as CI runs it

Each comparison alternates its two sides over several rounds in one run and reports
the median of the per-round ratios, so machine noise mostly cancels. Servers and
clients run in their own processes, as a controller and a console would.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import platform
import pty
import select
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from console_bench import console_run, start_simulator  # noqa: E402

try:
    import uvloop  # noqa: F401  (the optional extra: measured when installed)

    HAVE_UVLOOP = True
except ImportError:
    HAVE_UVLOOP = False

RESPONDER = r"""
import socket, sys
server = socket.socket()
server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
server.bind(("127.0.0.1", 0))
server.listen(8)
print(server.getsockname()[1], flush=True)
while True:
    conn, _ = server.accept()
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    try:
        while data := conn.recv(65536):
            conn.sendall(b"0,3,123\r" * data.count(b"\r"))
    except OSError:
        pass  # a client that aborts its connection
    conn.close()
"""

BARE_SOCKET_CLIENT = r"""
import socket, sys, time
port, seconds = int(sys.argv[1]), float(sys.argv[2])
sock = socket.create_connection(("127.0.0.1", port))
sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
request, count, buffer = b"GET:RC8:10:I:\r", 0, b""
started = time.perf_counter()
while time.perf_counter() - started < seconds:
    for _ in range(100):
        sock.sendall(request)
        while b"\r" not in buffer:
            buffer += sock.recv(4096)
        line, _, buffer = buffer.partition(b"\r")
    count += 100
print(count / (time.perf_counter() - started))
"""

SESSION_CLIENT = r"""
import asyncio, os, sys, time
if os.environ.get("RAC_BENCH_UVLOOP"):
    import uvloop
    asyncio.set_event_loop_policy(uvloop.EventLoopPolicy())
from rac_console.client import RacSession
from rac_console.protocol import kind_of
async def main(port, seconds, sessions):
    kind = kind_of("I")
    clients = [RacSession("127.0.0.1", port) for _ in range(sessions)]
    counts = [0] * sessions
    started = time.perf_counter()
    async def loop(n):
        while time.perf_counter() - started < seconds:
            for _ in range(100):
                await clients[n].get(kind, 10)
            counts[n] += 100
    await asyncio.gather(*(loop(n) for n in range(sessions)))
    print(sum(counts) / (time.perf_counter() - started))
    for client in clients:
        await client.close()
asyncio.run(main(int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])))
"""


def python(code: str, *args: object, uvloop: bool = False) -> float:
    env = os.environ | ({"RAC_BENCH_UVLOOP": "1"} if uvloop else {})
    out = subprocess.run(
        [sys.executable, "-c", code, *map(str, args)],
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
        env=env,
    ).stdout
    return float(out.split()[-1])


def c_client() -> Path | None:
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        return None
    binary = Path(tempfile.gettempdir()) / "rac_bench_client"
    subprocess.run(
        [compiler, "-O2", "-o", str(binary), str(HERE / "c" / "rac_client.c")], check=True
    )
    return binary


def run_c(binary: Path, port: int, sessions: int, seconds: float) -> float:
    out = subprocess.run(
        [str(binary), str(port), str(sessions), str(seconds)],
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
    ).stdout
    return float(out)


def start_responder() -> tuple[subprocess.Popen[str], int]:
    process = subprocess.Popen([sys.executable, "-c", RESPONDER], stdout=subprocess.PIPE, text=True)
    assert process.stdout is not None
    return process, int(process.stdout.readline())


def alternate(rounds: int, **sides) -> dict[str, list[float]]:
    """Run each side once per round, in turn, so noise hits every side alike."""
    results: dict[str, list[float]] = {name: [] for name in sides}
    for _ in range(rounds):
        for name, measure in sides.items():
            results[name].append(measure())
    return results


def ratio(results: dict[str, list[float]], top: str, bottom: str) -> float:
    return statistics.median(a / b for a, b in zip(results[top], results[bottom], strict=True))


def median(values: list[float]) -> float:
    return statistics.median(values)


# ----------------------------------------------------------------- the sections


def client_section(seconds: float, rounds: int, binary: Path | None) -> dict[str, float]:
    responder, port = start_responder()
    try:
        sides = {
            "bare": lambda: python(BARE_SOCKET_CLIENT, port, seconds),
            "client": lambda: python(SESSION_CLIENT, port, seconds, 1),
        }
        if binary:
            sides["c"] = lambda: run_c(binary, port, 1, seconds)
        if HAVE_UVLOOP:
            sides["uvloop"] = lambda: python(SESSION_CLIENT, port, seconds, 1, uvloop=True)
        results = alternate(rounds, **sides)
    finally:
        responder.kill()
    out = {
        "responder_bare_python_rps": median(results["bare"]),
        "responder_client_rps": median(results["client"]),
        "client_to_bare_ratio": ratio(results, "client", "bare"),
    }
    if binary:
        out["responder_c_rps"] = median(results["c"])
        out["client_to_c_ratio"] = ratio(results, "client", "c")
    if HAVE_UVLOOP:
        out["responder_client_uvloop_rps"] = median(results["uvloop"])
        out["client_uvloop_to_bare_ratio"] = ratio(results, "uvloop", "bare")
    return out


def simulator_section(seconds: float, rounds: int, binary: Path | None) -> dict[str, float]:
    simulator, port = start_simulator()
    try:
        sides = {"client": lambda: python(SESSION_CLIENT, port, seconds, 1)}
        if binary:
            sides["c1"] = lambda: run_c(binary, port, 1, seconds)
            sides["c50"] = lambda: run_c(binary, port, 50, seconds)
        else:
            sides["c50"] = lambda: python(SESSION_CLIENT, port, seconds, 50)
        results = alternate(rounds, **sides)
    finally:
        simulator.terminate()
        simulator.wait()
    out = {
        "simulator_client_rps": median(results["client"]),
        "simulator_50_sessions_rps": median(results["c50"]),
    }
    if binary:
        out["simulator_1_session_rps"] = median(results["c1"])
    return out


async def watch_polling(seconds: float, rounds: int) -> dict[str, float]:
    """100 watched variables through the console engine (no screen) vs the bare client."""
    from rac_console.core import ConsoleCore

    simulator, port = start_simulator()
    try:
        core = ConsoleCore("127.0.0.1", port, interval=0.0)
        await core.start()
        await core.handle_line("watch I 0-49")
        await core.handle_line("watch IO 0-49")
        bare, polled = [], []
        for _ in range(rounds):
            core.set_paused(True)
            await asyncio.sleep(0.1)
            bare.append(await asyncio.to_thread(python, SESSION_CLIENT, port, seconds, 1))
            core.set_paused(False)
            before, started = core.polls, time.perf_counter()
            await asyncio.sleep(seconds)
            polled.append((core.polls - before) / (time.perf_counter() - started))
        await core.stop()
    finally:
        simulator.terminate()
        simulator.wait()
    return {
        "watch_polls_per_s": median(polled),
        "watch_to_bare_ratio": statistics.median(p / b for p, b in zip(polled, bare, strict=True)),
    }


def first_paint(runs: int) -> float:
    """Process start to the first screen that names its target, in a real pty."""
    times = []
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as home:
            env = os.environ | {
                "HOME": home,
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
    return median(times) if times else float("nan")


def version_time(runs: int) -> float:
    times = []
    for _ in range(runs):
        started = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "rac_console", "--version"], check=True, capture_output=True
        )
        times.append(time.perf_counter() - started)
    return median(times)


# ------------------------------------------------------------------------ report

TARGETS = [
    (
        "client_to_bare_ratio",
        "session client / bare Python socket loop",
        ">= 0.80",
        lambda v: v >= 0.8,
    ),
    ("client_to_c_ratio", "session client / C client (the floor)", "reported", None),
    (
        "client_uvloop_to_bare_ratio",
        "session client on uvloop / bare loop",
        ">= 0.80",
        lambda v: v >= 0.8,
    ),
    ("watch_to_bare_ratio", "watch polling / bare client", ">= 0.90", lambda v: v >= 0.9),
    (
        "simulator_50_sessions_rps",
        "simulator requests/s over 50 sessions",
        ">= 50,000",
        lambda v: v >= 50_000,
    ),
    ("key_median_ms", "key press handled while polling, median ms", "< 50", lambda v: v < 50),
    ("key_p95_ms", "key press handled while polling, p95 ms", "< 100", lambda v: v < 100),
    ("memory_growth", "memory 10k -> N frames (ratio)", "<= 1.20", lambda v: v <= 1.2),
    ("first_paint_s", "cold start to first paint, s", "< 1", lambda v: v < 1),
    ("version_s", "rac-console --version, s", "< 0.3", lambda v: v < 0.3),
]


def report(results: dict[str, float]) -> None:
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
        f"{platform.python_version()}, {platform.system()} {platform.release()}"
    )
    width = 46
    print(f"{'figure':<{width}} {'value':>12}  target     verdict")
    for key, label, target, check in TARGETS:
        if key not in results:
            continue
        value = results[key]
        verdict = "" if check is None else ("met" if check(value) else "MISSED")
        print(f"{label:<{width}} {value:>12,.3f}  {target:<10} {verdict}")
    print()
    for key, value in sorted(results.items()):
        if isinstance(value, float):
            print(f"  {key} = {value:,.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: checks it runs")
    parser.add_argument("--seconds", type=float, default=2.0, help="length of each round")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument(
        "--frames",
        type=int,
        default=1_000_000,
        help="frames through the console before memory is read",
    )
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    args = parser.parse_args()
    if args.smoke:
        args.seconds, args.rounds, args.frames = 0.3, 1, 3_000
    binary = c_client()
    results: dict[str, float] = {}
    results |= client_section(args.seconds, args.rounds, binary)
    results |= simulator_section(args.seconds, args.rounds, binary)
    results |= asyncio.run(watch_polling(args.seconds, args.rounds))
    simulator, port = start_simulator()
    try:
        console = asyncio.run(console_run(port, args.seconds, args.rounds, args.frames))
    finally:
        simulator.terminate()
        simulator.wait()
    results |= {k: float(v) for k, v in console.items() if v is not None}
    results["memory_growth"] = console["memory_after_mb"] / console["memory_10k_frames_mb"]
    results["first_paint_s"] = first_paint(1 if args.smoke else 5)
    results["version_s"] = version_time(1 if args.smoke else 9)
    report(results)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
