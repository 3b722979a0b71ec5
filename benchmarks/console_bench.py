"""Console benchmark: 100 watched variables polled against the simulator.

    python benchmarks/console_bench.py [--seconds 5] [--frames 200000] [--json FILE]

Prints, in one run so that machine noise mostly cancels in the ratios:
  - the bare session client's GET rate against the simulator (no UI);
  - the console's poll rate with 100 watched variables at interval 0, the frame log
    visible, and its ratio to the bare rate (target >= 0.8);
  - key-press handling time while polling at full speed (median, p95; target < 50 ms);
  - process memory at start and after a long run of frames (the log is bounded).
The simulator runs in its own process (``rac-console sim --port 0``), as a controller would.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rac_console.client import RacSession
from rac_console.core import ConsoleCore
from rac_console.history import History
from rac_console.protocol import kind_of
from rac_console.tui.app import RacConsoleApp

VARIABLES = [(kind_of(code), index) for code in ("I", "F", "D", "P", "J") for index in range(10)]
VARIABLES += [(kind_of("IO"), index) for index in range(50)]


def rss_mb() -> float:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def start_simulator() -> tuple[subprocess.Popen[str], int]:
    process = subprocess.Popen([sys.executable, "-m", "rac_console", "sim", "--port", "0"],
                               stdout=subprocess.PIPE, text=True)
    assert process.stdout is not None
    line = process.stdout.readline()
    port = int(line.split(":")[1].split()[0])
    return process, port


async def bare_rate(port: int, seconds: float) -> float:
    session = RacSession("127.0.0.1", port)
    count, deadline = 0, time.perf_counter() + seconds
    started = time.perf_counter()
    while time.perf_counter() < deadline:
        for kind, index in VARIABLES:
            await session.get(kind, index)
        count += len(VARIABLES)
    rate = count / (time.perf_counter() - started)
    await session.close()
    return rate


async def console_run(port: int, seconds: float, frames_target: int) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as home:
        core = ConsoleCore("127.0.0.1", port, interval=0.0)
        app = RacConsoleApp(core, History(Path(home) / "history"))
        async with app.run_test(size=(120, 40)) as pilot:
            await pilot.pause(0.3)
            memory_start = rss_mb()
            app.command_line.insert_text_at_cursor("watch IO 0-49")
            await pilot.press("enter")
            for code in ("I", "F", "D", "P", "J"):
                app.command_line.insert_text_at_cursor(f"watch {code} 0-9")
                await pilot.press("enter")
            await pilot.pause(1.0)  # warm up
            polls_before, started = core.polls, time.perf_counter()
            latencies = []
            while time.perf_counter() - started < seconds:
                pressed = time.perf_counter()
                await pilot.press("x")
                latencies.append((time.perf_counter() - pressed) * 1000)
                await pilot.press("backspace")
                await pilot.pause(0.1)
            rate = (core.polls - polls_before) / (time.perf_counter() - started)
            memory_polling = rss_mb()
            while app.frame_log.frames_seen < frames_target:
                await pilot.pause(0.5)
            memory_after = rss_mb()
            frames = app.frame_log.frames_seen
    latencies.sort()
    return {
        "console_polls_per_s": rate,
        "key_median_ms": statistics.median(latencies),
        "key_p95_ms": latencies[int(len(latencies) * 0.95) - 1],
        "key_samples": len(latencies),
        "memory_start_mb": memory_start,
        "memory_polling_mb": memory_polling,
        "memory_after_mb": memory_after,
        "frames": frames,
    }


async def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--frames", type=int, default=200_000)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args()
    simulator, port = start_simulator()
    try:
        bare = await bare_rate(port, args.seconds)
        results = {"bare_client_gets_per_s": bare, **await console_run(port, args.seconds,
                                                                       args.frames)}
    finally:
        simulator.terminate()
        simulator.wait()
    results["console_to_bare_ratio"] = results["console_polls_per_s"] / bare
    rows = [
        ("bare client GETs/s (100 variables, no UI)", f"{bare:,.0f}", ""),
        ("console polls/s (100 watched, log visible)", f"{results['console_polls_per_s']:,.0f}",
         ""),
        ("console / bare", f"{results['console_to_bare_ratio']:.2f}", ">= 0.80"),
        ("key press handled, median ms", f"{results['key_median_ms']:.1f}", "< 50"),
        ("key press handled, p95 ms", f"{results['key_p95_ms']:.1f}", ""),
        ("memory at start, MB", f"{results['memory_start_mb']:.0f}", ""),
        ("memory while polling, MB", f"{results['memory_polling_mb']:.0f}", ""),
        (f"memory after {results['frames']:,} frames, MB", f"{results['memory_after_mb']:.0f}",
         "flat"),
    ]
    width = max(len(r[0]) for r in rows)
    print(f"{'measure':<{width}}  {'value':>10}  target")
    for name, value, target in rows:
        print(f"{name:<{width}}  {value:>10}  {target}")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    asyncio.run(main())
