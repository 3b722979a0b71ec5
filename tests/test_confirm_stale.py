"""A confirm question whose write has already ended (a cancel came first) is not left
on screen asking about nothing."""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.engine import ConfirmWrite, Message, Result
from rac_console.tui.confirm_screen import ConfirmWriteScreen
from tests.support.drivers import make_app, until

pytestmark = pytest.mark.slow


async def test_a_question_whose_result_came_closes(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await until(pilot, lambda: app.main_screen.status is not None, "the first status")
        question = ConfirmWrite(99, "I10", "14", "15", "PUT:RC8:10:I:3,15", "LIVE h:5006", None)
        app.main_screen.members.engine.outbox.put_many([question])
        await until(pilot, lambda: isinstance(app.screen, ConfirmWriteScreen), "the question")
        app.main_screen.members.engine.outbox.put_many(
            [Result(99, (Message("not run: cancelled", "error"),))]
        )
        await until(pilot, lambda: not isinstance(app.screen, ConfirmWriteScreen), "it closes")


async def test_the_questions_readiness_tick_after_it_closed_is_harmless(tmp_path: Path) -> None:
    """The keys line's tick (every 0.05 s) can come once more while the question closes,
    its widgets gone: it once raised NoMatches there, and ended the console."""
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await until(pilot, lambda: app.main_screen.status is not None, "the first status")
        question = ConfirmWrite(99, "I10", "14", "15", "PUT:RC8:10:I:3,15", "LIVE h:5006", None)
        app.main_screen.members.engine.outbox.put_many([question])
        await until(pilot, lambda: isinstance(app.screen, ConfirmWriteScreen), "the question")
        screen = app.screen
        assert isinstance(screen, ConfirmWriteScreen)
        app.main_screen.members.engine.outbox.put_many([Result(99, (Message("not run"),))])
        await until(pilot, lambda: not screen.is_attached, "it closes, its widgets gone")
        await until(pilot, lambda: screen.accepting, "its guard time over")
        screen._show_readiness()  # the tick that came late
        assert app.is_running
