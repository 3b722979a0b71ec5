"""The views opened on a row, the trend (``t``) and the detail (``d``), leave the table
the focus (issue 41): the row keys go on working (``↓ t`` the next row's trend, ``T`` an
overlay in a cell, ``d``), and Esc on the table closes the view open, the next key still
the table's; Esc again goes to the command line."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.sim.cell import SimulatedCellThread
from rac_console.tui.app import RacConsoleApp
from tests.support.cells import make_cell_app, row
from tests.support.drivers import make_app, type_line, until

#: Terminal apps on simulators: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow


@pytest.fixture
def two() -> Iterator[SimulatedCellThread]:
    with SimulatedCellThread(2) as sims:
        yield sims


def escape_says(app: RacConsoleApp) -> str:
    """What Esc does now, as the footer and the help read it."""
    return app.screen.active_bindings["escape"].binding.description


async def test_after_t_the_table_keeps_the_keys(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        panes = app.main_screen.panes
        await type_line(pilot, "watch I 0-1")
        await until(pilot, lambda: panes.table.row_count == 2, "the two rows")
        await pilot.press("f6", "t")
        await until(pilot, lambda: panes.trend_view.has_class("-open"), "I0's trend")
        assert str(panes.trend_view.var) == "I0"
        assert app.focused is panes.table, "t took the focus from the table"
        assert escape_says(app) == "Close view"
        await pilot.press("down", "t")  # the next row's trend, from where the keys are
        await until(pilot, lambda: str(panes.trend_view.var) == "I1", "I1's trend")
        await pilot.press("d")  # the detail in the trend's place
        await until(pilot, lambda: panes.row_detail.is_open, "the detail")
        assert not panes.trend_view.has_class("-open")
        assert app.focused is panes.table
        assert panes.command_line.value == ""


async def test_in_a_cell_T_right_after_t_overlays_the_next_row(
    tmp_path: Path, two: SimulatedCellThread
) -> None:
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        panes = app.main_screen.panes
        await type_line(pilot, "@robotA watch IO 128")
        await type_line(pilot, "@robotB watch IO 64")
        await until(
            pilot,
            lambda: None not in (row(app, "robotA", "IO128"), row(app, "robotB", "IO64")),
            "a row on each target",
        )
        await pilot.press("f6", "t", "down", "T")  # no F6 between: the table kept the keys
        view = panes.trend_view
        await until(pilot, lambda: len(view.series) == 2, "robotB's IO64 over robotA's IO128")
        assert [(t, str(v)) for t, v, _ in view.series] == [("robotA", "IO128"), ("robotB", "IO64")]
        assert app.focused is panes.table


async def test_esc_closes_the_view_and_the_next_key_is_the_tables(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        panes = app.main_screen.panes
        await type_line(pilot, "watch P 1")
        await type_line(pilot, "watch J 1")
        await until(pilot, lambda: panes.table.row_count == 2, "the two rows")
        await pilot.press("f6", "d")
        await until(pilot, lambda: panes.row_detail.is_open, "the detail")
        await pilot.press("escape")
        assert not panes.row_detail.is_open, "Esc left the detail open"
        assert panes.frame_log.display  # the log back in its place
        assert app.focused is panes.table
        assert escape_says(app) == "Command line"
        # Queued at once, as a fast hand's: the d after the Esc is the table's again.
        for key in ("d", "escape", "d"):
            app.simulate_key(key)
        await until(pilot, lambda: panes.row_detail.is_open, "the detail again")
        assert app.focused is panes.table and panes.command_line.value == ""
        await pilot.press("escape", "t")  # the detail closed, P1's trend open
        await until(pilot, lambda: panes.trend_view.has_class("-open"), "the trend")
        assert not panes.row_detail.is_open
        await pilot.press("escape")
        assert not panes.trend_view.has_class("-open") and panes.frame_log.display
        assert app.focused is panes.table
        await pilot.press("escape")  # nothing left open: to the command line
        assert app.focused is panes.command_line
