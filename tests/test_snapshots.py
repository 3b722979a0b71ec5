"""Snapshot tests of the console's main screen (pytest-textual-snapshot).

The screen shows live data, so the snapshot stages it: polling paused, rows filled
from the simulator's own values, frames with fixed timestamps.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from tui_helpers import make_app, type_line

from rac_console.client import Frame
from rac_console.protocol import kind_of
from rac_console.tui.app import RacConsoleApp

STAGED_FRAMES = [
    ("tx", b"GET:RC8:1:P:\r", None),
    ("rx", b"0,8196,350,0,450,180,0,180,5\r", 0.00031),
    ("tx", b"PUT:RC8:10:IO:11,-1\r", None),
    ("rx", b"0\r", 0.00022),
    ("tx", b"PUT:RC8:10:11,0\r", None),
    ("rx", b"-2147418107\r", 0.00019),
    ("rx", b"\xff\xfe0,3\r", 0.00020),
]


@pytest.fixture
def utc(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()


def stage(app: RacConsoleApp) -> None:
    core = app.core
    assert core.simulator is not None and core.session is not None
    now = time.monotonic()
    for n, row in enumerate(core.watch.rows.values()):
        row.update(core.simulator.controller.variant(row.var.kind, row.var.index), now - 5.5)
        if n == 2:
            row.fail("TIMEOUT", now)
    core.session.last_rtt = 0.00025
    app.frame_log.clear()
    for n, (direction, data, rtt) in enumerate(STAGED_FRAMES):
        app.frame_log.add(Frame(1_700_000_000.125 + n * 0.001, direction, data, rtt))  # type: ignore[arg-type]
    app.command_line.cursor_blink = False


def test_main_screen(snap_compare, tmp_path: Path, utc: None) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        app.core_thread.call(app.core.set_paused, True)
        for line in (
            "watch P 1 pick",
            "watch J 1 home",
            "watch I 4 parts",
            "watch IO 128-131",
            "watch S 1",
        ):
            await type_line(pilot, line)
        await pilot.pause(0.2)
        stage(app)
        app.flush_log()
        app._flushes.clear()  # no frames/s figure: it depends on timing
        app.refresh_table()
        await pilot.pause(0.1)

    assert snap_compare(app, terminal_size=(120, 34), run_before=run_before)


def test_main_screen_small_terminal(snap_compare, tmp_path: Path, utc: None) -> None:
    app = make_app(tmp_path, read_only=True)

    async def run_before(pilot) -> None:
        app.core_thread.call(app.core.set_paused, True)
        await type_line(pilot, "watch IO 128-131")
        await type_line(pilot, "put I 1 5")
        await pilot.pause(0.2)
        stage(app)
        app.flush_log()
        app._flushes.clear()  # no frames/s figure: it depends on timing
        app.refresh_table()
        await type_line(pilot, "put P 10 ", enter=False)
        await pilot.pause(0.2)

    assert snap_compare(app, terminal_size=(80, 24), run_before=run_before)


def test_completion_candidates(snap_compare, tmp_path: Path, utc: None) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        app.command_line.cursor_blink = False
        await pilot.press(*"get ")
        await pilot.press("tab")
        await pilot.pause(0.1)

    assert snap_compare(app, terminal_size=(100, 30), run_before=run_before)


def test_kind_labels_used_on_screen() -> None:
    assert kind_of("P").value_hint == "X Y Z Rx Ry Rz Fig"
