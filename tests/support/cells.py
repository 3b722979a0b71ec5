"""Helpers for the console on a cell: simulators in one process, a Cell on them."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path

from rac_console.commands.policy import TargetProfile, WritePolicy, Writes
from rac_console.commands.target import Target
from rac_console.engine import Alert, Result, RowView
from rac_console.engine.cell.cell import Cell
from rac_console.engine.commands.registry import Where
from rac_console.engine.published.outbox import Batch
from rac_console.engine.setup.options import EngineOptions
from rac_console.present.batches import BatchReader
from rac_console.present.history import History
from rac_console.sim.cell import SimulatedCellThread
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import REQUEST_TIMEOUT

COLOURS = ("green", "magenta", "cyan", "yellow")


def cell_targets(
    sims: SimulatedCellThread, confirm: tuple[str, ...] = ()
) -> list[tuple[str, Target]]:
    """A profile per simulator (its name, a colour, a label); the names in ``confirm``
    ask before every write."""
    targets = []
    for n, (name, host, port) in enumerate(sims.cell.addresses):
        writes = Writes.CONFIRM if name in confirm else Writes.OPEN
        policy = WritePolicy(writes)
        profile = TargetProfile(name, host, port, f"Cell {name[-1]}", COLOURS[n], policy)
        targets.append((name, Target(host, port, profile=profile, policy=policy)))
    return targets


def make_cell_app(
    tmp_path: Path,
    sims: SimulatedCellThread,
    *,
    confirm: tuple[str, ...] = (),
    interval: float = 0.05,
    timeout: float = REQUEST_TIMEOUT,
) -> RacConsoleApp:
    """The console on a cell of the simulators, on a private history."""
    options = EngineOptions(timeout=timeout, interval=interval, cycles=True)
    cell = Cell(cell_targets(sims, confirm), options=options, where=Where.CONSOLE)
    return RacConsoleApp(cell, History(tmp_path / "history"))


def row(app: RacConsoleApp, name: str, var: str) -> RowView | None:
    """A target's row of the variable named ``var`` (``IO128``), as the console holds it."""
    return next(
        (r for r in app.main_screen.members.states[name].rows.values() if str(r.var) == var), None
    )


#: A wait this long means hung: never a figure a test checks.
DEADLINE = 10.0
#: A wait on the cell's notify asks its condition again at least this often (a file the
#: engines write, which no event announces).
RECHECK = 0.5


class CellFront(BatchReader):
    """A front end in miniature for a cell: woken by the cell's notify, as the console
    and the REPL are; keeps what it published (read as every front end reads it).
    Every wait has a deadline."""

    def __init__(self, cell: Cell) -> None:
        self.cell = cell
        self.woke = threading.Event()
        cell.set_notify(self.woke.set)
        self.results: dict[int, tuple[str | None, Result]] = {}
        self.batches: dict[str | None, list[Batch]] = {}
        self.alerts: list[tuple[str | None, str]] = []

    def drain(self) -> None:
        for name, batch in self.cell.drain():
            self.batches.setdefault(name, []).append(batch)
            self.read(name, batch)

    def take_result(self, target: str | None, result: Result) -> None:
        self.results[result.seq] = (target, result)

    def take_alert(self, target: str | None, alert: Alert) -> None:
        self.alerts.append((target, alert.text))

    def until(self, holds: Callable[[], bool], what: str, timeout: float = DEADLINE) -> None:
        deadline = time.monotonic() + timeout
        while True:
            self.woke.clear()  # before the drain: a publish after it wakes the wait
            self.drain()
            if holds():
                return
            remaining = deadline - time.monotonic()
            assert remaining > 0, f"timed out waiting for {what}"
            self.woke.wait(min(remaining, RECHECK))

    def result(self, seq: int) -> tuple[str | None, Result]:
        """The Result numbered ``seq``, and the target it came from (None: the cell's)."""
        self.until(lambda: seq in self.results, f"result {seq}")
        return self.results[seq]

    def run(self, line: str) -> list[str]:
        """Submit a line and wait for its answer: what it said, as text."""
        _, result = self.result(self.cell.submit(line))
        return [getattr(f, "text", None) or str(f) for f in result.feedback]
