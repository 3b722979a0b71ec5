"""Snapshot tests of the watch table with its cursor and trends, and of the trend view.

Staged like tests/test_snapshots.py: polling paused, rows from the simulator's own
values, and the trend store fed a fixed sequence of cycles so the bars hold still.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path

import pytest

from rac_console.engine import Cycle
from rac_console.protocol import Variant
from rac_console.protocol.vartypes import VT, VT_ARRAY
from rac_console.tui import panes as panes_module
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import HeldClock, make_app, stage, until, watch_then_pause

pytestmark = pytest.mark.slow

LINES = ("watch P 1 pick", "watch IO 128-131", "watch I 4 parts", "watch S 1")


def feed_trends(app: RacConsoleApp, cycles: int = 40) -> None:
    """Replace what polling gathered by a fixed sequence of cycles, 0.5 s apart."""
    app.main_screen.members.trends.clear()
    rows = {str(var): var for var in app.main_screen.members.rows}
    assert app.main_screen.status is not None
    target = app.main_screen.status.target_id  # the cycles of the target on screen
    for n in range(cycles):
        z = 450 + 20 * math.sin(n / 4)
        samples = [
            (rows["P1"], Variant(VT.R4 | VT_ARRAY, [350.0, 0.0, z, 180.0, 0.0, 180.0, 5.0])),
            (rows["IO128"], Variant(VT.BOOL, n % 6 < 3)),
            (rows["IO129"], Variant(VT.BOOL, False)),
            (rows["IO130"], None if n % 10 == 7 else Variant(VT.BOOL, True)),
            (rows["I4"], Variant(VT.I4, n * 3 % 50)),
            (rows["S1"], Variant(VT.BSTR, "")),
        ]
        app.main_screen.feed.take_cycle(
            None, Cycle(1_700_000_000 + n / 2, 1000 + n / 2, tuple(samples), target)
        )


async def staged(pilot) -> None:
    app = pilot.app
    await watch_then_pause(pilot, LINES, rows=7)
    await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "no frames flowing")
    stage(app)
    feed_trends(app)
    app.main_screen.flush_log()
    # No frames/s figure (it depends on timing): let the staged frames' rate fall to 0.
    await until(
        pilot, lambda: app.main_screen.frames_per_second() == 0, "the staged frames' rate to pass"
    )


def hold_ages(app: RacConsoleApp, monkeypatch: pytest.MonkeyPatch) -> None:
    """The ages as stage() set them, just before the screenshot (the waits moved them),
    and held there: the table's clock stands still until the screenshot, which a busy
    machine may take seconds to come to (the clock's tick would draw "6s")."""
    now = time.monotonic()
    for var, view in list(app.main_screen.members.rows.items()):
        app.main_screen.members.rows[var] = replace(view, changed_at=now - 5.001)
    monkeypatch.setattr(panes_module, "time", HeldClock(now))
    app.main_screen.refresh_table()


@pytest.mark.usefixtures("utc")
def test_table_focused_with_a_cursor_and_trends(
    snap_compare, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        await staged(pilot)
        await pilot.press("f6", "down", "s")  # the cursor on IO128, sorted by name
        hold_ages(app, monkeypatch)
        await pilot.pause(0.1)

    assert snap_compare(app, terminal_size=(120, 34), run_before=run_before)


@pytest.mark.usefixtures("utc")
def test_trend_view_small_terminal(
    snap_compare, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        await staged(pilot)
        await pilot.press("f6", "t", "f", "f")  # P1's trend, its Z field
        hold_ages(app, monkeypatch)
        await pilot.pause(0.1)

    assert snap_compare(app, terminal_size=(80, 24), run_before=run_before)


@pytest.mark.usefixtures("utc")
def test_row_detail_small_terminal(
    snap_compare, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``d`` on P1 at 80x24: the row the table cuts after Y, a field a line."""
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        await staged(pilot)
        await pilot.press("f6", "d")
        await until(
            pilot, lambda: "Fig" in app.main_screen.panes.row_detail.shown_text, "the detail"
        )
        hold_ages(app, monkeypatch)
        await pilot.pause()  # the held ages drawn (messages processed, no time waited)

    assert snap_compare(app, terminal_size=(80, 24), run_before=run_before)
