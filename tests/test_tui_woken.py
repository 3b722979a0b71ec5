"""The console is woken by the engine: no timer drains the outbox, one clock ticks."""

from __future__ import annotations

from pathlib import Path

import pytest
from textual.timer import Timer
from tui_helpers import log_text, make_app, until

from rac_console.tui import app as app_module
from rac_console.tui.app import OutboxWoke, RacConsoleApp


class Noting(RacConsoleApp):
    """The console, counting the engine's wakes it handles."""

    CSS_PATH = Path(app_module.__file__).with_name("app.tcss")  # beside the app, not here
    woken = 0

    def on_outbox_woke(self, message: OutboxWoke) -> None:
        self.woken += 1
        super().on_outbox_woke(message)


def running_timers(app: RacConsoleApp) -> list[Timer]:
    """The app's own timers still running (Textual keeps them in ``_timers``)."""
    return [timer for timer in app._timers if timer._task is not None and not timer._task.done()]


@pytest.mark.slow  # over half a second
async def test_the_only_timer_is_the_clock_and_a_get_reaches_the_log_when_the_engine_notifies(
    tmp_path: Path,
) -> None:
    base = make_app(tmp_path)
    app = Noting(base.engine, base.history)
    async with app.run_test() as pilot:
        await until(
            pilot,
            lambda: app.status is not None and app.status.connection == "connected",
            "the connection",
        )
        await until(pilot, lambda: len(running_timers(app)) == 1, "one timer left")
        clock = app._clock
        assert running_timers(app) == [clock]

        clock.pause()  # nothing periodic at all: only the engine's notify wakes the app
        woken = app.woken
        app.submit_line("get I 1")
        await until(pilot, lambda: "GET:RC8:1:I:" in log_text(app), "the GET's request")
        await until(pilot, lambda: "← " in log_text(app).split("GET:RC8:1:I:")[-1], "its reply")
        assert app.woken > woken  # brought by the engine's wakes


async def test_wakes_while_one_is_queued_are_one(tmp_path: Path) -> None:
    first, second = OutboxWoke(), OutboxWoke()
    assert second.can_replace(first)
