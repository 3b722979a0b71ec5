"""A snapshot of the console on a cell of two simulators at 120x40: the Target column,
a badge per target, the prompt naming the current one, the log naming each frame's
target, results naming theirs. Staged as the main screen's snapshot is (polling paused,
ages, round trips, frames and trends fixed)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest

from rac_console.engine import Cycle
from rac_console.session import Frame
from rac_console.sim.cell import SimulatedCellThread
from rac_console.tui.app import RacConsoleApp
from tests.support.cells import make_cell_app
from tests.support.drivers import hold_still, type_line, until

pytestmark = [pytest.mark.slow, pytest.mark.usefixtures("utc")]

#: A handshake that does not start while the snapshot is taken: every value holds still.
STILL = {"cycle": 1000.0, "hold": 1.0, "reaction": 0.35}

STAGED = [
    ("robotA", "tx", b"GET:RC8:128:IO:\r", None),
    ("robotA", "rx", b"0,11,-1\r", 0.00031),
    ("robotB", "tx", b"GET:RC8:64:IO:\r", None),
    ("robotB", "rx", b"0,11,0\r", 0.00042),
    ("robotB", "tx", b"PUT:RC8:10:I:3,7\r", None),
    ("robotB", "rx", b"0\r", 0.00022),
]


@pytest.fixture
def two() -> Iterator[SimulatedCellThread]:
    with SimulatedCellThread(2, **STILL) as sims:
        yield sims


def stage(app: RacConsoleApp) -> float:
    now = time.monotonic()
    for state in app.main_screen.members.states.values():
        for var, view in list(state.rows.items()):
            state.rows[var] = replace(view, changed_at=now - 5.001)
        assert state.status is not None
        state.status = replace(state.status, rtt=0.00025)
        state.trends.clear()
        samples = tuple((var, view.variant) for var, view in state.rows.items())
        for n in range(20):
            cycle = Cycle(1_700_000_000 + n / 2, 1000 + n / 2, samples, state.status.target_id)
            app.main_screen.feed.take_cycle(state.name, cycle)
    app.main_screen.panes.frame_log.clear()
    for n, (name, direction, data, rtt) in enumerate(STAGED):
        frame = Frame(1_700_000_000.125 + n * 0.001, direction, data, rtt)  # type: ignore[arg-type]
        app.main_screen.panes.frame_log.add(frame, name)
    app.main_screen.panes.command_line.cursor_blink = False
    return now


def test_cell_view_120x40(
    snap_compare, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, two
) -> None:
    app = make_cell_app(tmp_path, two)

    async def run_before(pilot) -> None:
        await until(
            pilot,
            lambda: all(
                s.status is not None and s.status.connection == "connected"
                for s in app.main_screen.members.states.values()
            ),
            "both connected",
        )
        for line in (
            "watch IO 128 part placed",
            "watch I 10 parts",
            "@robotB watch IO 64 go",
            "@robotB watch I 10 parts",
        ):
            await type_line(pilot, line)
        await until(
            pilot,
            lambda: (
                sum(len(s.rows) for s in app.main_screen.members.states.values()) == 4
                and all(
                    v.status == "OK"
                    for s in app.main_screen.members.states.values()
                    for v in s.rows.values()
                )
            ),
            "every row's first value",
        )
        await pilot.press("f2")  # every target's polls paused
        await until(
            pilot,
            lambda: all(
                s.status is not None and s.status.paused
                for s in app.main_screen.members.states.values()
            ),
            "the pause",
        )
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "no frames flowing")
        hold_still(app, monkeypatch, stage(app), frames_per_second=0)
        app.main_screen.flush_log()
        app.main_screen.refresh_table()
        await pilot.pause()

    assert snap_compare(app, terminal_size=(120, 40), run_before=run_before)
