"""Alive all shift: the console keeps drawing what its engines publish, whatever
becomes of a one-shot timer, and a screen that stalled or an engine that died is said.

Textual ends a one-shot timer without calling it when its delay has passed by the time
its task first reads the clock (``Timer._run``: a skipped tick ends a ``repeat=0``
timer); another thread holding the GIL across that moment loses delays of
milliseconds. :func:`short_one_shots_lost` makes that certain for every one-shot timer
shorter than a limit, so the console's drawing is judged with them all lost.
"""

from __future__ import annotations

import gc
import json
import shutil
import subprocess
import sys
from collections.abc import Awaitable, Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from textual.pilot import Pilot
from textual.timer import Timer

from rac_console.engine.commands import jobs
from rac_console.tui.app import OutboxWoke, RacConsoleApp

from .support.drivers import connected, log_text, make_app, results_text, type_line, until

#: Over half a second each (a console under a flood): `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"
LOSING = ("--lose-below", "0.005", "--json")
#: Longer than any wait the console's pacing computes (it puts an update off by at most
#: a fifth of a second): with this, every one of those timers is lost.
LOST_BELOW = 0.25


@pytest.fixture
def short_one_shots_lost(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[float]]:
    """Textual as it is when the clock has passed a one-shot timer's delay before the
    timer first reads it: the timer ends without calling back. Yields the delays lost."""
    lost: list[float] = []
    run = Timer._run

    async def run_or_lose(self: Timer) -> None:
        if self._repeat == 0 and self._interval < LOST_BELOW:
            lost.append(self._interval)
            return  # as Textual's skip ends a one-shot whose delay has passed
        await run(self)

    monkeypatch.setattr(Timer, "_run", run_or_lose)
    yield lost


@dataclass
class Shown:
    """What the console shows of the flood, sampled: each new sight is counted."""

    app: RacConsoleApp
    seen: dict[str, list[str]] = field(default_factory=dict)

    def sample(self) -> None:
        table = self.app.main_screen.panes.table
        looks = {"log": newest_log_line(self.app)}
        for row in ("F0", "J0"):
            looks[row] = str(table.get_cell(row, "value")) if row in table.rows else ""
        for what, text in looks.items():
            kept = self.seen.setdefault(what, [])
            if not kept or kept[-1] != text:
                kept.append(text)

    def changes(self, what: str) -> int:
        return len(self.seen.get(what, [])) - 1


def newest_log_line(app: RacConsoleApp) -> str:
    lines = log_text(app).splitlines()
    return lines[-1] if lines else ""


async def watching_a_flood(pilot: Pilot[Any], app: RacConsoleApp) -> None:
    """The issue's flood: 24 rows polled back to back, the frame log on screen."""
    await connected(pilot, app)
    await type_line(pilot, "watch F 0 J 0 I 0-19 P 0 T 0")
    await type_line(pilot, "interval 0")


async def each_keeps_changing(pilot: Pilot[Any], shown: Shown, rounds: int) -> None:
    """The log's newest line and the F0 and J0 values change ``rounds`` times more."""
    start = {what: shown.changes(what) for what in ("log", "F0", "J0")}

    def moved() -> bool:
        shown.sample()
        return all(shown.changes(what) >= start[what] + rounds for what in start)

    await until(pilot, moved, f"the log, F0 and J0 to change {rounds} times more: {shown.seen}")


async def answered(pilot: Pilot[Any], app: RacConsoleApp, n: int) -> None:
    """A typed ``get`` reaches the results pane."""
    await type_line(pilot, f"get I {n}")
    await until(pilot, lambda: f"I{n} = " in results_text(app), f"the answer to get I {n}")


async def run_console(
    tmp_path: Path, steps: Callable[[Pilot[Any], RacConsoleApp], Awaitable[None]]
) -> None:
    app = make_app(tmp_path, interval=0.2)
    async with app.run_test(size=(120, 40)) as pilot:
        await steps(pilot, app)


async def test_with_every_short_one_shot_timer_lost_the_console_goes_on_drawing(
    tmp_path: Path, short_one_shots_lost: list[float]
) -> None:
    async def steps(pilot: Pilot[Any], app: RacConsoleApp) -> None:
        await watching_a_flood(pilot, app)
        shown = Shown(app)
        for n in range(3):
            await each_keeps_changing(pilot, shown, 3)
            await answered(pilot, app, 50 + n)

    await run_console(tmp_path, steps)


async def test_a_screen_that_missed_every_wake_catches_up_and_says_it_was_behind(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def lost(self: RacConsoleApp, _: OutboxWoke) -> None:
        """The engines' wakes never arrive (whatever the cause, the screen stalls)."""

    monkeypatch.setattr(RacConsoleApp, "on_outbox_woke", lost)

    async def steps(pilot: Pilot[Any], app: RacConsoleApp) -> None:
        await watching_a_flood(pilot, app)
        shown = Shown(app)
        await each_keeps_changing(pilot, shown, 2)
        await answered(pilot, app, 50)
        bar = app.main_screen.panes.status_bar
        await until(pilot, lambda: "BEHIND, caught up" in bar.line.plain, "the status line's word")
        said = "the screen had not shown what the engine published for"
        await until(pilot, lambda: said in newest_log_line(app), "the log's line, newest")

    await run_console(tmp_path, steps)


def status_line(app: RacConsoleApp) -> str:
    return app.main_screen.panes.status_bar.line.plain


async def test_an_engine_that_died_is_said_in_red_and_answers_every_line_after(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    run_job = jobs.run_job

    def dies_on_get_i_13(registry: Any, context: Any, what: Any, where: Any, line: Any) -> Any:
        if line == "get I 13":
            raise RuntimeError("a bug")
        return run_job(registry, context, what, where, line)

    monkeypatch.setattr(jobs, "run_job", dies_on_get_i_13)

    async def steps(pilot: Pilot[Any], app: RacConsoleApp) -> None:
        await connected(pilot, app)
        await type_line(pilot, "watch I 0")
        await until(pilot, lambda: "connected" in status_line(app), "connected")
        await type_line(pilot, "get I 13")
        await until(
            pilot,
            lambda: "ENGINE STOPPED" in status_line(app),
            "the engine said dead: " + status_line(app) + results_text(app),
        )
        assert "connected" not in status_line(app)
        said = [
            span for span in app.main_screen.panes.status_bar.line.spans if "red" in str(span.style)
        ]
        assert said, "ENGINE STOPPED is said in red"
        await until(pilot, lambda: "has stopped (RuntimeError: a bug)" in results_text(app), "why")
        await type_line(pilot, "get I 1")
        await until(
            pilot,
            lambda: "not run: this target's engine has stopped" in results_text(app),
            "the line typed after, answered",
        )
        assert not app.main_screen.lines.pending

    await run_console(tmp_path, steps)


@pytest.mark.skipif(shutil.which("tmux") is None, reason="needs tmux (.ci/run installs it)")
def test_the_soak_in_a_real_terminal_keeps_drawing_with_short_timers_lost(tmp_path: Path) -> None:
    """The hour's soak (benchmarks/console_soak.py), shortened: the real console in tmux
    under a flood, one-shot timers under 5 ms lost. Judged on what reached the screen:
    every put typed answered there, and the values and the log went on changing."""
    figures = tmp_path / "soak.json"
    subprocess.run(
        [
            sys.executable,
            str(BENCHMARKS / "console_soak.py"),
            "--seconds",
            "25",
            *LOSING,
            str(figures),
        ],
        check=True,
        timeout=300,
        capture_output=True,
    )
    seen = json.loads(figures.read_text())
    assert seen["keys"] >= 2 and seen["keys_unanswered"] == 0, seen
    assert all(seen["changes"].get(what, 0) >= 5 for what in ("F0", "J0", "log")), seen
    assert seen["said_engine_stopped"] == 0, seen


def live(kind: type) -> int:
    """How many objects of ``kind`` are alive (what a leak keeps counts here)."""
    gc.collect()
    return sum(isinstance(thing, kind) for thing in gc.get_objects())


async def test_the_footers_old_keys_go_with_each_line_run(tmp_path: Path) -> None:
    """Each line run changes the keys shown (Esc cancels), and the footer is composed
    again: Textual kept every old key, data-bound to the footer's ``compact``, until that
    changed, which it never does: about 430 KB a line, for as long as the console ran."""
    from textual.widgets._footer import FooterKey

    async def steps(pilot: Pilot[Any], app: RacConsoleApp) -> None:
        await connected(pilot, app)
        await answered(pilot, app, 50)
        before = live(FooterKey)
        for n in range(30):
            await answered(pilot, app, 51 + n % 40)
        assert live(FooterKey) <= 2 * before, (before, live(FooterKey))

    await run_console(tmp_path, steps)


async def test_the_style_caches_of_the_footers_old_keys_go_with_them(tmp_path: Path) -> None:
    """Textual keeps the style cache of up to 1,024 widgets gone, each with the lines it
    drew (an ``lru_cache`` on a method holds it): the footer's old keys, nine a line
    run, kept theirs, about 4 KB each, 4 MB once full."""
    from textual._styles_cache import StylesCache

    async def steps(pilot: Pilot[Any], app: RacConsoleApp) -> None:
        await connected(pilot, app)
        await answered(pilot, app, 50)
        before = live(StylesCache)
        for n in range(30):
            await answered(pilot, app, 51 + n % 40)
        assert live(StylesCache) < before + 30, (before, live(StylesCache))  # not one a line

    await run_console(tmp_path, steps)
