"""What one queue for a cell costs: typed lines run one at a time across targets.

    python benchmarks/cell_queue.py [--lines 400] [--rounds 3]

A cell of two simulated targets (in this process) runs ``--lines`` lines that alternate
between the targets (``@robotA get I 1``, ``@robotB get I 1``), woken by the cell's notify
as a front end is. Side by side, each round:

- ``one queue``: through :meth:`Cell.submit`, the next line started when the one before
  has answered, on its engine's thread (lines in the order typed, whatever target they
  name);
- ``per engine``: the same lines handed straight to each target's engine, as before
  the queue (each engine runs its own in order, the targets side by side).

Printed: milliseconds per line, the median of the rounds, and their ratio.
"""

from __future__ import annotations

import argparse
import statistics
import threading
import time

from rac_console.commands.target import Target
from rac_console.engine.cell.cell import Cell
from rac_console.engine.published.events import Result
from rac_console.engine.setup.options import EngineOptions
from rac_console.sim.cell import SimulatedCellThread


def _cell(sims: SimulatedCellThread) -> tuple[Cell, threading.Event]:
    targets = [(name, Target(host, port)) for name, host, port in sims.cell.addresses]
    cell = Cell(targets, options=EngineOptions(timeout=2.0, interval=10.0))
    woke = threading.Event()
    cell.set_notify(woke.set)
    cell.start()
    return cell, woke


def _wait(cell: Cell, woke: threading.Event, count: int) -> None:
    seen = 0
    deadline = time.monotonic() + 120
    while seen < count:
        woke.clear()
        for _, batch in cell.drain():
            seen += sum(isinstance(event, Result) and event.seq > 0 for event in batch.events)
        if seen < count:
            assert time.monotonic() < deadline, "results did not come"
            woke.wait(0.5)


def one_round(sims: SimulatedCellThread, lines: int, queued: bool) -> float:
    cell, woke = _cell(sims)
    try:
        names = list(cell.names)
        cell.drain()
        start = time.perf_counter()
        for n in range(lines):
            name = names[n % 2]
            if queued:
                cell.submit(f"@{name} get I 1")
            else:
                cell.member(name).engine.submit("get I 1")
        _wait(cell, woke, lines)
        return (time.perf_counter() - start) / lines * 1000
    finally:
        cell.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--lines", type=int, default=400)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    with SimulatedCellThread(2) as sims:
        queue, direct = [], []
        for _ in range(args.rounds):
            queue.append(one_round(sims, args.lines, True))
            direct.append(one_round(sims, args.lines, False))
    q, d = statistics.median(queue), statistics.median(direct)
    print(f"{args.lines} lines alternating between 2 targets, median of {args.rounds} rounds")
    print(f"one queue   {q:7.3f} ms/line")
    print(f"per engine  {d:7.3f} ms/line")
    print(f"ratio       {q / d:7.2f}x")


if __name__ == "__main__":
    main()
