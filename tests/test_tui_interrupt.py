"""Ctrl+C in the console (issue 20.8): it cancels the running line as Esc does, from any
pane, as it does in the REPL and the CLI; with nothing running it says how to quit
(Ctrl+Q), and a selection in the command line is still copied."""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import FrameTap, make_app, results_text, type_line, until

pytestmark = pytest.mark.slow


def notices(app: RacConsoleApp) -> str:
    return "\n".join(notification.message for notification in app._notifications)


@pytest.mark.parametrize("pane", ["command line", "watch table"])
async def test_ctrl_c_cancels_a_wait_and_the_lines_queued_behind_it(
    tmp_path: Path, pane: str
) -> None:
    app = make_app(tmp_path)
    tap = FrameTap(tmp_path)
    async with app.run_test(size=(120, 30)) as pilot:
        await type_line(pilot, "wait I 1 >= 100 within 60")
        await until(pilot, lambda: b"GET:RC8:1:I:\r" in tap.sent, "the wait's first read")
        await type_line(pilot, "put IO 20 on")  # typed while the wait runs: queued
        await until(pilot, lambda: len(app.main_screen.lines.pending) == 2, "the put queued")
        if pane == "watch table":
            await pilot.press("f6")
            assert app.focused is app.main_screen.panes.table
        await pilot.press("ctrl+c")
        await until(pilot, lambda: "not run" in results_text(app), "the queued line's answer")
        assert "wait cancelled" in results_text(app)
        assert not any(frame.startswith(b"PUT:") for frame in tap.sent)
        await until(pilot, lambda: not app.main_screen.lines.pending, "nothing running")
        assert app.is_running


async def test_ctrl_c_with_nothing_running_says_ctrl_q_quits(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 30)) as pilot:
        await until(pilot, lambda: app.main_screen.status is not None, "the first status")
        await type_line(pilot, "get I", enter=False)
        await pilot.press("ctrl+c")
        await until(pilot, lambda: "Ctrl+Q" in notices(app), "the notice")
        assert "quits" in notices(app)
        assert app.is_running
        assert app.main_screen.panes.command_line.value == "get I"  # nothing typed is lost


async def test_ctrl_c_copies_a_selection_in_the_command_line(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 30)) as pilot:
        await type_line(pilot, "get P 10", enter=False)
        await pilot.press("shift+home")  # select the line
        await pilot.press("ctrl+c")
        await until(pilot, lambda: app.clipboard == "get P 10", "the copy")
        assert "Ctrl+Q" not in notices(app)


async def test_ctrl_c_while_a_write_asks_cancels_it(tmp_path: Path) -> None:
    from rac_console.sim.thread import SimulatorThread
    from tests.support.drivers import burst, confirm_console, connected, modal

    with SimulatorThread() as cell:
        app = confirm_console(tmp_path, cell)
        tap = FrameTap(tmp_path)
        async with app.run_test(size=(100, 30)) as pilot:
            await connected(pilot, app)
            burst(app, "put IO 67 on\r")
            await until(pilot, lambda: modal(app) is not None, "the question")
            await pilot.press("ctrl+c")
            await until(pilot, lambda: modal(app) is None, "the question closed")
            await until(pilot, lambda: not app.main_screen.lines.pending, "the write ended")
            assert not any(frame.startswith(b"PUT:") for frame in tap.sent)
