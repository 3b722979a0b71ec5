"""Keys typed ahead of a write's question on a ``confirm`` target (issue 20.5).

``put IO 67 on``, Enter, ``y``, Enter typed in one burst must not run ``y`` as a command
once the question is answered: keys typed between the write's Enter and the question,
or while it is up, never reach the command line. When the write ends without asking
(refused by the profile's ``allow``), the keys held meanwhile are typed in, in order.

The burst is posted to the app in one go, so every key of it is on its way before the
engine has even read the line: no timing decides which keys come before the question.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.present.type_ahead import may_ask
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import (
    FrameTap,
    answerable,
    burst,
    confirm_console,
    connected,
    declined_with_keys_typed_ahead,
    modal,
    results_text,
    until,
)

pytestmark = pytest.mark.slow


@pytest.fixture
def cell() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


async def test_keys_typed_before_the_question_never_reach_the_command_line(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = confirm_console(tmp_path, cell)
    tap = FrameTap(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await connected(pilot, app)
        await declined_with_keys_typed_ahead(pilot, app)
        await until(pilot, lambda: "not confirmed" in results_text(app), "the answer's result")
        await pilot.pause(0.3)  # anything typed ahead would have run by now
        results = results_text(app)
        assert "› y" not in results and "unknown command" not in results, results
        assert "2 keys typed ahead of the question were ignored" in results
        assert app.main_screen.panes.command_line.value == ""
        assert not any(frame.startswith(b"PUT:") for frame in tap.sent)
        assert not app.main_screen.lines.pending
        # The command line is the user's again: a line typed now runs.
        burst(app, "get I 1\r")
        await until(pilot, lambda: "› get I 1" in results_text(app), "the next line")


async def test_keys_held_for_a_write_that_did_not_ask_are_typed_in_in_order(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = confirm_console(tmp_path, cell, allow="IO 0-10")
    async with app.run_test(size=(100, 30)) as pilot:
        await connected(pilot, app)
        burst(app, "put IO 67 on\rget I 1\rget I")
        await until(pilot, lambda: "› get I 1" in results_text(app), "the line typed ahead")
        results = results_text(app)
        assert "refused" in results.partition("› put IO 67 on")[2]
        assert modal(app) is None
        assert (
            app.main_screen.panes.command_line.value == "get I"
        )  # the unfinished line, to go on typing
        assert "typed ahead" not in results


async def test_a_write_queued_behind_a_running_line_holds_no_keys(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = confirm_console(tmp_path, cell)
    async with app.run_test(size=(100, 30)) as pilot:
        await connected(pilot, app)
        burst(app, "wait I 1 >= 100 within 30\r")
        await until(pilot, lambda: bool(app.main_screen.lines.pending), "the wait running")
        burst(app, "put IO 67 on\rget I")
        await until(
            pilot, lambda: app.main_screen.panes.command_line.value == "get I", "the keys typed in"
        )
        assert modal(app) is None
        await pilot.press("escape")  # the wait and the put behind it end
        await until(pilot, lambda: not app.main_screen.lines.pending, "the cancel")


@pytest.mark.parametrize(
    ("line", "asks"),
    [
        ("put IO 67 on", True),
        ("put P 1 1 2 3 4 5 6 7", True),
        ("PUT:RC8:10:I:3,5", True),
        ("send hello", True),  # not a well-formed GET: the target's rules apply
        ("get IO 67", False),
        ("GET:RC8:10:I:", False),
        ("watch IO 0-7", False),
        ("wait I 1 >= 5 within 2", False),
        ("put IO", False),  # refused before anything is asked
        ("y", False),
        ("", False),
    ],
)
def test_which_lines_may_ask_before_they_write(line: str, asks: bool) -> None:
    assert may_ask(line) is asks


async def test_keys_typed_after_space_on_a_row_do_not_reach_the_command_line(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = confirm_console(tmp_path, cell)
    async with app.run_test(size=(100, 30)) as pilot:
        await connected(pilot, app)
        burst(app, "watch IO 67\r")
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 1, "the row")
        await until(
            pilot,
            lambda: next(iter(app.main_screen.members.rows.values())).status == "OK",
            "its value",
        )
        await pilot.press("f6")
        assert app.focused is app.main_screen.panes.table
        burst(app, " y\r")  # Space writes the opposite, y and Enter typed after it
        await until(pilot, lambda: modal(app) is not None, "the question", timeout=3)
        screen = modal(app)
        assert screen is not None
        await answerable(pilot, screen)
        await pilot.press("n")
        await until(pilot, lambda: "not confirmed" in results_text(app), "the answer's result")
        await pilot.pause(0.3)
        results = results_text(app)
        assert "› y" not in results and "unknown command" not in results, results
        assert app.main_screen.panes.command_line.value == ""


async def test_the_keys_dropped_are_said_after_the_answer_of_the_line_they_were_typed_behind(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    """The notice belongs to the write whose question dropped the keys: it comes after
    that line's echo and answer, never before them (where it would read as the previous
    line's)."""
    app = confirm_console(tmp_path, cell)
    async with app.run_test(size=(100, 30)) as pilot:
        await connected(pilot, app)
        await declined_with_keys_typed_ahead(pilot, app)
        notice = "2 keys typed ahead of the question were ignored"
        await until(
            pilot,
            lambda: "not confirmed" in results_text(app) and notice in results_text(app),
            "the answer and the notice",
        )
        results = results_text(app)
        echo = results.index("› put IO 67 on")
        assert echo < results.index("not confirmed") < results.index(notice), results
