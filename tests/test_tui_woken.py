"""The console is woken by the engine: no timer drains the outbox, one clock ticks."""

from __future__ import annotations

from pathlib import Path

import pytest
from textual.timer import Timer

from rac_console.tui import app as app_module
from rac_console.tui.app import OutboxWoke, RacConsoleApp
from tests.support.drivers import log_text, make_app, until


class Noting(RacConsoleApp):
    """The console, counting the engine's wakes it handles."""

    CSS_PATH = Path(app_module.__file__).with_name("app.tcss")  # type: ignore[assignment]  # beside the app, not here
    woken = 0

    def on_outbox_woke(self, message: OutboxWoke) -> None:
        self.woken += 1
        super().on_outbox_woke(message)


def running_timers(app: RacConsoleApp) -> list[Timer]:
    """The console's own timers still running: the app's, and its screen's but for the
    repaint timer Textual gives every screen (Textual keeps them in ``_timers``)."""
    screen = [t for t in app.main_screen._timers if t.name != "screen_update"]
    return [t for t in [*app._timers, *screen] if t._task is not None and not t._task.done()]


@pytest.mark.slow  # over half a second
async def test_the_clock_and_the_watchdog_are_the_only_timers_and_the_engine_wakes_the_log(
    tmp_path: Path,
) -> None:
    base = make_app(tmp_path)
    app = Noting(base.main_screen.members.engine, base.main_screen.history)
    async with app.run_test() as pilot:
        await until(
            pilot,
            lambda: (
                app.main_screen.status is not None
                and app.main_screen.status.connection == "connected"
            ),
            "the connection",
        )
        await until(pilot, lambda: len(running_timers(app)) == 2, "two timers left")
        clock, watchdog = app.main_screen.pacing.clock, app.watchdog_timer
        assert clock is not None and watchdog is not None
        assert set(running_timers(app)) == {clock, watchdog}

        clock.pause()  # nothing periodic at all: only the engine's notify wakes the app
        watchdog.pause()
        woken = app.woken
        app.main_screen.submit_line("get I 1")
        await until(pilot, lambda: "GET:RC8:1:I:" in log_text(app), "the GET's request")
        await until(pilot, lambda: "← " in log_text(app).split("GET:RC8:1:I:")[-1], "its reply")
        assert app.woken > woken  # brought by the engine's wakes


async def test_wakes_while_one_is_queued_are_one(tmp_path: Path) -> None:
    first, second = OutboxWoke(), OutboxWoke()
    assert second.can_replace(first)
