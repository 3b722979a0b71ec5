"""Try the console on a simulated cell: COUNT simulators playing the handshake (robotA's
IO 128 "part placed", robotB's IO 64 "go" a moment later), the console on all of them.

    python scripts/cell_console.py [COUNT] [--confirm NAME]...

Each simulator is a profile of its own (a colour, a label); ``--confirm robotB`` makes
robotB's writes ask first. The history is private to the run.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from rac_console.commands.policy import TargetProfile, WritePolicy, Writes
from rac_console.commands.target import Target
from rac_console.engine.cell.cell import Cell
from rac_console.engine.commands.registry import Where
from rac_console.engine.setup.options import EngineOptions
from rac_console.present.history import History
from rac_console.sim.cell import SimulatedCellThread
from rac_console.tui.app import run_console

COLOURS = ("green", "magenta", "cyan", "yellow", "blue", "red", "white", "bright_black")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("count", nargs="?", type=int, default=2)
    parser.add_argument("--confirm", action="append", default=[], metavar="NAME")
    parser.add_argument("--watch", action="store_true", help="watch the handshake's bits")
    args = parser.parse_args()
    with SimulatedCellThread(args.count) as sims, tempfile.TemporaryDirectory() as home:
        targets = []
        for n, (name, host, port) in enumerate(sims.cell.addresses):
            policy = WritePolicy(Writes.CONFIRM if name in args.confirm else Writes.OPEN)
            profile = TargetProfile(name, host, port, f"Cell {name[-1]}", COLOURS[n], policy)
            targets.append((name, Target(host, port, profile=profile, policy=policy)))
        options = EngineOptions(interval=0.2, cycles=True)
        cell = Cell(targets, options=options, where=Where.CONSOLE)
        if args.watch:  # queued before the start: run once connected
            cell.submit("@robotA watch IO 128 part placed")
            if args.count > 1:
                cell.submit("@robotB watch IO 64 go")
        return run_console(cell, History(Path(home) / "history"), None)


if __name__ == "__main__":
    sys.exit(main())
