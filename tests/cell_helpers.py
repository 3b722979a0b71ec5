"""Helpers for the console on a cell: simulators in one process, a Cell on them."""

from __future__ import annotations

from pathlib import Path

from rac_console.commands.policy import TargetProfile, WritePolicy, Writes
from rac_console.commands.target import Target
from rac_console.engine import RowView
from rac_console.engine.cell import Cell
from rac_console.engine.options import EngineOptions
from rac_console.engine.registry import Where
from rac_console.present.history import History
from rac_console.sim.cell import SimulatedCellThread
from rac_console.tui.app import RacConsoleApp

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
    timeout: float = 1.0,
) -> RacConsoleApp:
    """The console on a cell of the simulators, on a private history."""
    options = EngineOptions(timeout=timeout, interval=interval, cycles=True)
    cell = Cell(cell_targets(sims, confirm), options=options, where=Where.CONSOLE)
    return RacConsoleApp(cell, History(tmp_path / "history"))


def row(app: RacConsoleApp, name: str, var: str) -> RowView | None:
    """A target's row of the variable named ``var`` (``IO128``), as the console holds it."""
    return next((r for r in app.states[name].rows.values() if str(r.var) == var), None)
