"""Snapshot tests of the console's main screen (pytest-textual-snapshot).

The screen shows live data, so the snapshot stages it: polling paused, rows filled
from the simulator's own values, frames with fixed timestamps.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.present.completion import hint
from rac_console.protocol import kind_of
from tests.support.drivers import hold_still, make_app, stage, type_line, until, watch_then_pause

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow


def test_main_screen(
    snap_compare, tmp_path: Path, utc: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        lines = ("watch P 1 pick", "watch J 1 home", "watch I 4 parts", "watch IO 128-131")
        await watch_then_pause(pilot, (*lines, "watch S 1"), rows=8)
        # No polled frames still to come into the log before it is staged.
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "no frames flowing")
        hold_still(app, monkeypatch, stage(app), frames_per_second=4)
        app.main_screen.flush_log()
        app.main_screen.refresh_table()
        await pilot.pause()

    assert snap_compare(app, terminal_size=(120, 34), run_before=run_before)


def test_main_screen_small_terminal(
    snap_compare, tmp_path: Path, utc: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    app = make_app(tmp_path, read_only=True)

    async def run_before(pilot) -> None:
        await watch_then_pause(pilot, ("watch IO 128-131",), rows=4)
        await type_line(pilot, "put I 1 5")
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "no frames flowing")
        hold_still(app, monkeypatch, stage(app), frames_per_second=0)
        app.main_screen.flush_log()
        app.main_screen.refresh_table()
        await type_line(pilot, "put P 10 ", enter=False)
        shown = "put P 10 " + hint("put P 10 ")  # the grey argument hint
        await until(
            pilot,
            lambda: app.main_screen.panes.command_line._suggestion == shown,
            "the argument hint",
        )

    assert snap_compare(app, terminal_size=(80, 24), run_before=run_before)


def test_completion_candidates(snap_compare, tmp_path: Path, utc: None) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        app.main_screen.panes.command_line.cursor_blink = False
        await pilot.press(*"get ")
        await pilot.press("tab")
        await pilot.pause(0.1)

    assert snap_compare(app, terminal_size=(100, 30), run_before=run_before)


@pytest.mark.parametrize("size", [(40, 12), (80, 24)], ids=["40x12", "80x24"])
def test_completion_list_over_the_panes(
    snap_compare,
    tmp_path: Path,
    utc: None,
    monkeypatch: pytest.MonkeyPatch,
    size: tuple[int, int],
) -> None:
    """Tab after ``get `` with J, T and IO rows watched: the list floats above the
    command line, which keeps its row; the table keeps its rows (at 40x12 the list has
    all the room there is, the log left out: the table and the results share it)."""
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        lines = ("watch J 1 home", "watch T 1", "watch IO 128-131")
        await watch_then_pause(pilot, lines, rows=6)
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "no frames flowing")
        hold_still(app, monkeypatch, stage(app), frames_per_second=0)
        app.main_screen.flush_log()
        app.main_screen.refresh_table()
        await pilot.press(*"get ", "tab")
        await until(pilot, lambda: app.main_screen.panes.completions.is_open, "the list")
        await pilot.pause()

    assert snap_compare(app, terminal_size=size, run_before=run_before)


def test_kind_labels_used_on_screen() -> None:
    assert kind_of("P").value_hint == "X Y Z Rx Ry Rz Fig"
