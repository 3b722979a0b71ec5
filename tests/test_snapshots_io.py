"""Snapshot of the I/O grid (F5) at 80x24: 64 bits in 4 lines of 16, a few labels.

Staged as in test_snapshots.py: polling paused, values fixed, frames with fixed times.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import pytest

from rac_console.protocol import Variant, kind_of
from rac_console.session import Frame
from tests.support.drivers import make_app, type_line, until

pytestmark = pytest.mark.slow

IO = kind_of("IO")
ON_BITS = {128, 130, 131, 144, 152, 159, 160, 161, 162, 163, 164, 165, 166, 167, 190}
LABELS = {128: "gripper closed", 130: "vacuum on", 131: "part present", 176: "door"}
STALE = 185


def test_io_grid_80x24(snap_compare, tmp_path: Path, utc: None) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        await type_line(pilot, "watch IO 128-191")
        await until(
            pilot,
            lambda: (
                len(app.main_screen.members.rows) == 64
                and all(v.status == "OK" for v in app.main_screen.members.rows.values())
            ),
            "every bit's first value",
        )
        await type_line(pilot, "pause")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.paused,
            "the pause",
        )
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "no frames flowing")
        assert app.main_screen.status is not None
        app.main_screen.members.status = replace(app.main_screen.status, rtt=0.00025)
        app.main_screen.panes.frame_log.clear()
        for n, data in enumerate((b"GET:RC8:128:IO:\r", b"0,11,-1\r")):
            direction = "tx" if n == 0 else "rx"
            app.main_screen.panes.frame_log.add(
                Frame(1_700_000_000.125 + n * 0.001, direction, data, 0.0002)  # type: ignore[arg-type]
            )
        app.main_screen.panes.command_line.cursor_blink = False
        await pilot.press("f5")
        app.main_screen.panes.io_panel.focus()
        await pilot.press("right", "right")  # the cursor on IO 130: its label below the grid
        app.main_screen.flush_log()
        # No frames/s figure (it depends on timing): wait for the staged frames' rate to fall.
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "the rate back to 0")
        # The rows last: their ages count from now, however long the rate took to fall.
        now = time.monotonic()
        for var, view in list(app.main_screen.members.rows.items()):
            app.main_screen.members.rows[var] = replace(
                view,
                label=LABELS.get(var.index, ""),
                variant=Variant(IO.vt, var.index in ON_BITS),
                changed_at=now - 5.001,
                status="TIMEOUT" if var.index == STALE else "OK",
                stale=var.index == STALE,
            )
        app.main_screen.refresh_table()
        await pilot.pause(0.2)

    assert snap_compare(app, terminal_size=(80, 24), run_before=run_before)
