"""Polling a cell: three targets of 100 rows each against three times one target.

    python benchmarks/cell_polling.py [--seconds 4] [--rounds 5] [--delay-ms 1]

A cell is one engine (one session, one thread) per controller, in one process. Each
round measures, in turn (the order turned each round):

- ``one``: a cell of one target watching I 0-99 at interval 0;
- ``three``: a cell of three targets, each watching I 0-99 at interval 0;

against two kinds of controller:

- ``controller-like``: ``rac-console sim --delay MS`` in its own process per target, a
  reply MS milliseconds after its request (an RC8 on a cell's network answers in
  about a millisecond or more): the client mostly waits, as at a cell;
- ``flat out``: the C responder (``cc -O2``), one per target, answering at once: every
  poll is the client's CPU, and the three engines share one interpreter's GIL.

Polls are counted from the engines' own poll cycles (``Cycle``, as the console's
trends see them) over the measured window. The target: ``three`` >= 0.8 x 3 x ``one``
for the controller-like case. The flat-out figure is printed beside it: there the
ceiling is one core of Python for the whole process, whatever the number of targets.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from bench_common import CPrograms, Server  # noqa: E402
from sim_harness import SimulatorProcess  # noqa: E402

from rac_console.commands.target import Target  # noqa: E402
from rac_console.engine import Cycle, EngineOptions  # noqa: E402
from rac_console.engine.cell.cell import Cell  # noqa: E402

ROWS = "I 0-99"
TARGET = 0.8


def polls_per_second(ports: list[int], seconds: float) -> float:
    """Polls a second of a cell on ``ports`` (one target each), all rows at interval 0."""
    woke = threading.Event()
    options = EngineOptions(interval=0.0, cycles=True, frames=False)
    members = [(f"t{n}", Target("127.0.0.1", port)) for n, port in enumerate(ports)]
    cell = Cell(members, options=options, notify=woke.set)
    cell.start()
    for member in cell.members:
        member.engine.submit(f"watch {ROWS}")
    polls, started, warm = 0, None, time.monotonic() + 1.0
    try:
        while True:
            woke.wait(0.2)
            woke.clear()
            now = time.monotonic()
            for _, batch in cell.drain():
                for event in batch.events:
                    if isinstance(event, Cycle) and started is not None:
                        polls += len(event.samples)
            if started is None and now >= warm:
                started = now
            elif started is not None and now - started >= seconds:
                return polls / (now - started)
    finally:
        cell.stop()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=4.0)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--delay-ms", type=float, default=1.0)
    args = parser.parse_args()
    programs = CPrograms()
    sims = [SimulatorProcess("--delay", f"{args.delay_ms:g}") for _ in range(3)]
    responders = (
        [Server([str(programs.responder), "0"]) for _ in range(3)] if programs.responder else []
    )
    kinds = {"controller-like": [s.port for s in sims], "flat out": [r.port for r in responders]}
    rates: dict[tuple[str, str], list[float]] = {}
    try:
        for round_ in range(args.rounds):
            sides = [
                (kind, size) for kind, ports in kinds.items() if ports for size in ("one", "three")
            ]
            if round_ % 2:
                sides.reverse()
            for kind, size in sides:
                ports = kinds[kind][: 1 if size == "one" else 3]
                rates.setdefault((kind, size), []).append(polls_per_second(ports, args.seconds))
            print(f"round {round_ + 1}/{args.rounds} done", flush=True)
    finally:
        for sim in sims:
            sim.stop()
        for responder in responders:
            responder.stop()
        programs.cleanup()
    print(
        f"\n{args.rounds} rounds of {args.seconds:g} s; "
        "3 targets x 100 rows against 1 x 100; medians"
    )
    print(
        f"{'controllers':<28} {'one polls/s':>12} {'three polls/s':>14} "
        f"{'three / (3 x one)':>18}  target"
    )
    for kind in kinds:
        if (kind, "one") not in rates:
            continue
        one = statistics.median(rates[kind, "one"])
        three = statistics.median(rates[kind, "three"])
        ratios = [
            t / (3 * o) for o, t in zip(rates[kind, "one"], rates[kind, "three"], strict=True)
        ]
        ratio = statistics.median(ratios)
        name = f"{kind} ({args.delay_ms:g} ms reply)" if kind == "controller-like" else kind
        goal = (
            f">= {TARGET}: {'met' if ratio >= TARGET else 'NOT met'}"
            if kind == "controller-like"
            else "reported (one interpreter's GIL)"
        )
        print(
            f"{name:<28} {one:>12,.0f} {three:>14,.0f} {ratio:>12.2f} "
            f"[{min(ratios):.2f}-{max(ratios):.2f}]  {goal}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
