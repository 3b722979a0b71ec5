"""Snapshot of a LIVE target profile's colours: the label in the profile's colour on the
status line and as the title of the frame around the whole console, ``CONFIRM WRITES``.

The controller is a simulator on 127.0.0.1 port 0; the figures that move (its port, the
round trip, frames per second) are staged.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from rac_console.commands.policy import TargetProfile, WritePolicy, Writes, parse_allow
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import console, type_line, until

#: A terminal app and a simulator: `pytest -m "not slow"` skips it.
pytestmark = pytest.mark.slow


def test_live_profile_colours(snap_compare, tmp_path: Path) -> None:
    with SimulatorThread() as cell:
        profile = TargetProfile(
            "cell3",
            cell.host,
            cell.port,
            "Cell 3 — welding",
            "dark_orange3",
            WritePolicy(Writes.CONFIRM, (parse_allow("I 100-199"),), "profile cell3"),
        )
        app = console(tmp_path, profile)

        async def run_before(pilot) -> None:
            await until(
                pilot,
                lambda: (
                    app.main_screen.status is not None
                    and app.main_screen.status.connection == "connected"
                ),
                "the connection",
            )
            await type_line(pilot, "pause")
            await until(
                pilot,
                lambda: app.main_screen.status is not None and app.main_screen.status.paused,
                "the pause",
            )
            await until(
                pilot, lambda: app.main_screen.frames_per_second() == 0, "no frames flowing"
            )
            assert app.main_screen.status is not None
            app.main_screen.members.status = replace(
                app.main_screen.status,
                target="LIVE 192.168.0.1:5006",
                host="192.168.0.1",
                port=5006,
                rtt=0.00025,
            )
            app.main_screen.panes.results.clear()
            app.main_screen.panes.frame_log.clear()
            app.main_screen.panes.command_line.cursor_blink = False
            app.main_screen.refresh_table()
            await pilot.pause(0.1)

        assert snap_compare(app, terminal_size=(100, 24), run_before=run_before)
