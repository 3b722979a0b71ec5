"""A long command in the console (a wait): shown while it runs, cancelled with Esc,
and the lines typed behind it are not run once it is cancelled."""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.tui.status_bar import StatusBar
from tests.support.drivers import FrameTap, make_app, results_text, type_line, until

pytestmark = pytest.mark.slow


def status_line(app) -> str:
    return str(app.query_one(StatusBar).render())


async def test_esc_cancels_a_wait_and_the_lines_queued_behind_it(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    tap = FrameTap(tmp_path)
    async with app.run_test(size=(120, 30)) as pilot:
        await type_line(pilot, "wait I 1 >= 100 within 60")
        await until(pilot, lambda: b"GET:RC8:1:I:\r" in tap.sent, "the wait's first read")
        await type_line(pilot, "put IO 20 on")  # typed while the wait runs: queued
        await until(pilot, lambda: "Esc cancels: wait I 1 >= 100" in status_line(app), "the sign")
        # The sign may be there from before the put: the count shows at the next refresh.
        await until(pilot, lambda: "+1 queued" in status_line(app), "the queued line counted")
        await pilot.press("escape")
        await until(pilot, lambda: "not run" in results_text(app), "the queued line's answer")
        results = results_text(app)
        assert "wait cancelled" in results
        assert "› put IO 20 on\n" in results + "\n"
        assert not any(frame.startswith(b"PUT:") for frame in tap.sent)
        await until(pilot, lambda: "Esc cancels" not in status_line(app), "the sign gone")
        await type_line(pilot, "put IO 20 on")  # a line typed after the cancel runs
        await until(pilot, lambda: b"PUT:RC8:20:IO:11,-1\r" in tap.sent, "the new put")


async def test_a_toggle_pressed_during_a_wait_is_queued_and_esc_drops_it(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    tap = FrameTap(tmp_path)
    async with app.run_test(size=(120, 30)) as pilot:
        await type_line(pilot, "watch IO 128")
        await until(
            pilot,
            lambda: (
                len(app.main_screen.members.rows) == 1
                and app.main_screen.panes.table.row_count == 1
            ),
            "the row",
        )
        await until(
            pilot,
            lambda: next(iter(app.main_screen.members.rows.values())).status == "OK",
            "its value",
        )
        await type_line(pilot, "wait I 1 >= 100 within 60")
        await until(pilot, lambda: b"GET:RC8:1:I:\r" in tap.sent, "the wait's first read")
        await pilot.press("f6", "space")  # a toggle of IO128, queued behind the wait
        await until(pilot, lambda: "+1 queued" in status_line(app), "the toggle counted")
        await pilot.press("escape")  # from the table back to the command line
        assert app.focused is app.main_screen.panes.command_line
        await pilot.press("escape")
        await until(pilot, lambda: "not run" in results_text(app), "the toggle dropped")
        assert not any(frame.startswith(b"PUT:") for frame in tap.sent)
