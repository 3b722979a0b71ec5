"""The status line's ``polls/s`` says how many GETs go out each second, as counted where
the controller receives them, and follows a change of the interval (issue 41: after
``interval 0.2`` it said 5, then 10 polls/s for over 20 s while a hundred went out each
second: the figure was one cycle's count over its period, and the cycles that polled
one row were the ones shown).

Here one row has its own ``every 0.05``: of the cycles 0.05 s apart, one in four (or
twenty) polls all the rows, the others that one row. The judgement is a band around the
count (half to twice it), never a figure the machine's load could move.
"""

from __future__ import annotations

import re
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from textual.pilot import Pilot

from rac_console.sim.thread import SimulatorThread
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import DEADLINE, make_app, type_line
from tests.support.servers import Valve

pytestmark = pytest.mark.slow

#: The controller's count is taken over this many seconds before a figure is judged.
WINDOW = 2.5

#: How far the figure may be from the count: a factor each way.
BAND = 2.0

#: Looks in a row (0.1 s apart at least) that must all agree: the figure holds, it does
#: not pass through the band on its way from one wrong value to another.
STEADY = 10

RATE = re.compile(r"(\d+) polls/s")


@pytest.fixture
def path() -> Iterator[Valve]:
    """The simulator behind a path that counts the requests reaching it."""
    with SimulatorThread() as sim:
        valve = Valve(sim.host, sim.port)
        try:
            yield valve
        finally:
            valve.close()


def shown_rate(app: RacConsoleApp) -> float | None:
    """The polls/s the status line shows, if it shows one."""
    found = RATE.search(app.main_screen.panes.status_bar.line.plain)
    return float(found.group(1)) if found else None


async def agreed(pilot: Pilot[int], app: RacConsoleApp, valve: Valve) -> float:
    """Watch the status line until its polls/s has agreed (within :data:`BAND`) with
    the requests the controller received over the last :data:`WINDOW` seconds at
    :data:`STEADY` looks in a row; the last figure. Only what happens from the call on
    is counted."""
    samples: list[tuple[float, int]] = []
    deadline = time.monotonic() + DEADLINE
    seen: list[tuple[float | None, int]] = []  # (shown, counted) at each look
    agreeing = 0
    while time.monotonic() < deadline:
        now = time.monotonic()
        samples.append((now, valve.requests))
        shown = shown_rate(app)
        first = next(((t, n) for t, n in samples if t >= now - WINDOW), samples[0])
        if now - samples[0][0] >= WINDOW and now > first[0]:
            counted = (samples[-1][1] - first[1]) / (now - first[0])
            seen.append((shown, round(counted)))
            if shown is not None and counted / BAND <= shown <= counted * BAND:
                agreeing += 1
                if agreeing >= STEADY:
                    return shown
            else:
                agreeing = 0
        await pilot.pause(0.1)
    raise AssertionError(
        f"polls/s did not agree with the controller's count (shown, counted): {seen[-STEADY:]}"
    )


async def test_polls_per_second_is_the_count_of_gets_and_follows_the_interval(
    tmp_path: Path, path: Valve
) -> None:
    app = make_app(tmp_path, "127.0.0.1", path.port, interval=1.0)
    async with app.run_test(size=(160, 40)) as pilot:
        await type_line(pilot, "watch I 0-39")
        await type_line(pilot, "watch IO 128 every 0.05")
        await agreed(pilot, app, path)  # about 60: 40 a second, and 20 of IO 128
        await type_line(pilot, "interval 0.2")
        # About 220 (200 a second, and 20) on a machine that keeps up: what is judged is
        # that the figure agrees with what the controller received since the change,
        # never how fast a busy machine polls.
        await agreed(pilot, app, path)
