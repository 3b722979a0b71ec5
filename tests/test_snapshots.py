"""Snapshot tests of the console's main screen (pytest-textual-snapshot).

The screen shows live data, so the snapshot stages it: polling paused, rows filled
from the simulator's own values, frames with fixed timestamps.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from tui_helpers import make_app, type_line, until

import rac_console.tui.app as app_module
from rac_console.engine import Cycle
from rac_console.present.completion import hint
from rac_console.protocol import kind_of
from rac_console.session import Frame
from rac_console.tui.app import RacConsoleApp

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

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


async def watch_then_pause(pilot, lines: tuple[str, ...], rows: int) -> None:
    """Watch, wait for every row's first value from the simulator, then pause."""
    app = pilot.app
    for line in lines:
        await type_line(pilot, line)
    await until(
        pilot,
        lambda: len(app.rows) == rows and all(v.status == "OK" for v in app.rows.values()),
        "every row's first value",
    )
    await type_line(pilot, "pause")
    await until(pilot, lambda: app.status is not None and app.status.paused, "the pause")


def stage(app: RacConsoleApp) -> float:
    """Fix what moves with the clock: ages, the round trip, one row timed out. Returns
    the moment the ages count from (see :func:`hold_still`)."""
    now = time.monotonic()
    for n, (var, view) in enumerate(list(app.rows.items())):
        view = replace(view, changed_at=now - 5.5)
        if n == 2:
            view = replace(view, status="TIMEOUT", stale=True)
        app.rows[var] = view
    assert app.status is not None
    app.status = replace(app.status, rtt=0.00025)
    app.frame_log.clear()
    for n, (direction, data, rtt) in enumerate(STAGED_FRAMES):
        app.frame_log.add(Frame(1_700_000_000.125 + n * 0.001, direction, data, rtt))  # type: ignore[arg-type]
    app.command_line.cursor_blink = False
    # The sparklines: as many samples as polling gathered would vary from run to run.
    app.trends.clear()
    samples = tuple((var, view.variant) for var, view in app.rows.items())
    assert app.status is not None
    target = app.status.target_id  # the cycles of the target on screen
    for n in range(20):
        app.take_cycle(Cycle(1_700_000_000 + n / 2, 1000 + n / 2, samples, target))
    return now


class HeldClock:
    """``time`` as the console's app module sees it, with ``monotonic()`` held at one
    moment (the rest is the real module)."""

    def __init__(self, now: float) -> None:
        self.now = now

    def monotonic(self) -> float:
        return self.now

    def __getattr__(self, name: str) -> Any:
        return getattr(time, name)


def hold_still(
    app: RacConsoleApp, monkeypatch: pytest.MonkeyPatch, now: float, frames_per_second: float
) -> None:
    """After :func:`stage`, until the screenshot: the table's clock held at ``now`` (the
    ages stay what stage() made them, "5s", however long the screenshot takes to come),
    and the log's rate staged (it counts the staged frames over however many refresh
    ticks the machine managed meanwhile: 3 or 4 frames/s as the load has it)."""
    monkeypatch.setattr(app_module, "time", HeldClock(now))
    monkeypatch.setattr(app, "frames_per_second", lambda: frames_per_second)


def test_main_screen(
    snap_compare, tmp_path: Path, utc: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        lines = ("watch P 1 pick", "watch J 1 home", "watch I 4 parts", "watch IO 128-131")
        await watch_then_pause(pilot, (*lines, "watch S 1"), rows=8)
        # No polled frames still to come into the log before it is staged.
        await until(pilot, lambda: app.frames_per_second() == 0, "no frames flowing")
        hold_still(app, monkeypatch, stage(app), frames_per_second=4)
        app.flush_log()
        app.refresh_table()
        await pilot.pause()

    assert snap_compare(app, terminal_size=(120, 34), run_before=run_before)


def test_main_screen_small_terminal(
    snap_compare, tmp_path: Path, utc: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    app = make_app(tmp_path, read_only=True)

    async def run_before(pilot) -> None:
        await watch_then_pause(pilot, ("watch IO 128-131",), rows=4)
        await type_line(pilot, "put I 1 5")
        await until(pilot, lambda: app.frames_per_second() == 0, "no frames flowing")
        hold_still(app, monkeypatch, stage(app), frames_per_second=0)
        app.flush_log()
        app.refresh_table()
        await type_line(pilot, "put P 10 ", enter=False)
        shown = "put P 10 " + hint("put P 10 ")  # the grey argument hint
        await until(pilot, lambda: app.command_line._suggestion == shown, "the argument hint")

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
