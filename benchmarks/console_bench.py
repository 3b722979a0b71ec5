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

from textual import events

from rac_console.core import ConsoleCore
from rac_console.history import History
from rac_console.tui.app import RacConsoleApp


def rss_mb() -> float:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def start_simulator() -> tuple[subprocess.Popen[str], int]:
    process = subprocess.Popen(
        [sys.executable, "-m", "rac_console", "sim", "--port", "0"],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert process.stdout is not None
    line = process.stdout.readline()
    port = int(line.split(":")[1].split()[0])
    return process, port


BARE_CLIENT = """
import asyncio, sys, time
from rac_console.client import RacSession
from rac_console.protocol import kind_of
VARIABLES = [(kind_of(c), i) for c in ("I", "F", "D", "P", "J") for i in range(10)]
VARIABLES += [(kind_of("IO"), i) for i in range(50)]
async def main(port, seconds):
    session = RacSession("127.0.0.1", port)
    count, started = 0, time.perf_counter()
    while time.perf_counter() - started < seconds:
        for kind, index in VARIABLES:
            await session.get(kind, index)
        count += len(VARIABLES)
    print(count / (time.perf_counter() - started))
    await session.close()
asyncio.run(main(int(sys.argv[1]), float(sys.argv[2])))
"""


async def bare_rate(port: int, seconds: float) -> float:
    """The session client alone, in its own process: no UI, no other thread."""
    process = await asyncio.create_subprocess_exec(
        sys.executable, "-c", BARE_CLIENT, str(port), str(seconds), stdout=asyncio.subprocess.PIPE
    )
    out, _ = await process.communicate()
    return float(out)


async def console_run(
    port: int, seconds: float, rounds: int, frames_target: int
) -> dict[str, float]:
    """Alternate rounds of the bare client (console paused) and of console polling."""
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
            bare, console, latencies, cpu_per_1000, frames_per_s = [], [], [], [], []
            memory_10k = None
            command_line = app.command_line
            for _ in range(rounds):
                app.core_thread.call(core.set_paused, True)
                await pilot.pause(0.2)
                bare.append(await bare_rate(port, seconds))
                app.core_thread.call(core.set_paused, False)
                await pilot.pause(0.2)
                polls_before, started = core.polls, time.perf_counter()
                cpu_before, frames_before = time.process_time(), app.frame_log.frames_seen
                while time.perf_counter() - started < seconds:
                    # A key event goes through the app's queue like a typed key; the time
                    # until the command line holds it is the key handling delay under load.
                    expected = command_line.value + "x"
                    pressed = time.perf_counter()
                    command_line.post_message(events.Key("x", "x"))
                    while command_line.value != expected:
                        await asyncio.sleep(0.0005)
                    latencies.append((time.perf_counter() - pressed) * 1000)
                    command_line.value = ""
                    await asyncio.sleep(0.1)
                console.append((core.polls - polls_before) / (time.perf_counter() - started))
                frames_in_round = app.frame_log.frames_seen - frames_before
                frames_per_s.append(frames_in_round / (time.perf_counter() - started))
                if frames_in_round:
                    cpu_per_1000.append(
                        (time.process_time() - cpu_before) / frames_in_round * 1000 * 1000
                    )
            memory_polling = rss_mb()
            while app.frame_log.frames_seen < frames_target:
                if memory_10k is None and app.frame_log.frames_seen >= 10_000:
                    memory_10k = rss_mb()
                await pilot.pause(0.2)
            memory_after = rss_mb()
            frames = app.frame_log.frames_seen
    latencies.sort()
    ratios = sorted(c / b for c, b in zip(console, bare, strict=True))
    return {
        "bare_client_gets_per_s": statistics.median(bare),
        "console_polls_per_s": statistics.median(console),
        "console_to_bare_ratio": statistics.median(ratios),
        "ratio_min": ratios[0],
        "ratio_max": ratios[-1],
        "key_median_ms": statistics.median(latencies),
        "key_p95_ms": latencies[int(len(latencies) * 0.95) - 1],
        "key_samples": len(latencies),
        "memory_start_mb": memory_start,
        "memory_polling_mb": memory_polling,
        "memory_10k_frames_mb": memory_10k if memory_10k is not None else memory_polling,
        "cpu_ms_per_1000_frames": statistics.median(cpu_per_1000) if cpu_per_1000 else None,
        "console_frames_per_s": statistics.median(frames_per_s),
        "memory_after_mb": memory_after,
        "frames": frames,
    }


async def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="length of each round")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=200_000)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args()
    simulator, port = start_simulator()
    try:
        results = await console_run(port, args.seconds, args.rounds, args.frames)
    finally:
        simulator.terminate()
        simulator.wait()
    bare = results["bare_client_gets_per_s"]
    rows = [
        ("bare client GETs/s (100 variables, no UI)", f"{bare:,.0f}", ""),
        (
            "console polls/s (100 watched, log visible)",
            f"{results['console_polls_per_s']:,.0f}",
            "",
        ),
        (
            "console / bare (median of rounds)",
            f"{results['console_to_bare_ratio']:.2f}",
            f">= 0.80  (rounds {results['ratio_min']:.2f}..{results['ratio_max']:.2f})",
        ),
        ("key press handled, median ms", f"{results['key_median_ms']:.1f}", "< 50"),
        ("key press handled, p95 ms", f"{results['key_p95_ms']:.1f}", ""),
        ("memory at start, MB", f"{results['memory_start_mb']:.0f}", ""),
        ("memory while polling, MB", f"{results['memory_polling_mb']:.0f}", ""),
        (
            f"memory after {results['frames']:,} frames, MB",
            f"{results['memory_after_mb']:.0f}",
            "flat",
        ),
    ]
    width = max(len(r[0]) for r in rows)
    print(f"{'measure':<{width}}  {'value':>10}  target")
    for name, value, target in rows:
        print(f"{name:<{width}}  {value:>10}  {target}")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    asyncio.run(main())
