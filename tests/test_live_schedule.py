"""The poll cycles' schedule (the console's, and ``get -r N -i S`` and ``watch --every
S``), on a clock the test holds.

:class:`Schedule` is given the clock's readings and says when each start is, and the
poller asks it, with the backoff's delay after a failure as a floor; so these tests pin
start-to-start timing exactly; the subprocess tests in test_cli_live.py only show that
the CLI runs on the engine's poller.
"""

from __future__ import annotations

import itertools

import pytest

from rac_console.engine.polling.backoff import FIRST_DELAY, MAX_DELAY, Backoff
from rac_console.engine.polling.schedule import Schedule

T0 = 1000.0  # any reading of a monotonic clock


def run(
    interval: float, durations: list[float], failing: frozenset[int] = frozenset()
) -> list[float]:
    """The starts of ``len(durations)`` repetitions, each taking its duration (from T0);
    the ones numbered in ``failing`` (from 0) end in a connection failure, after which
    the next start waits the backoff (as the poller retries)."""
    schedule, backoff = Schedule(), Backoff()
    clock, starts = T0, []
    for number, duration in enumerate(durations):
        start = schedule.start(clock, interval)
        assert start >= clock  # never in the past
        clock = start
        starts.append(start - T0)
        clock += duration
        if number in failing:
            schedule.not_before(clock + backoff.next_delay())
        else:
            backoff.good()
    return starts


def gaps(starts: list[float]) -> list[float]:
    return [b - a for a, b in itertools.pairwise(starts)]


def test_the_first_start_is_at_once() -> None:
    assert Schedule().start(T0, 5) == T0


@pytest.mark.parametrize("duration", [0.0, 0.01, 0.25, 0.99])
def test_reads_shorter_than_the_interval_start_an_interval_apart(duration: float) -> None:
    """Start to start: the read's own time is not added to the interval."""
    assert run(1.0, [duration] * 5) == pytest.approx([0, 1, 2, 3, 4])


def test_reads_as_long_as_the_interval_start_one_after_the_other() -> None:
    assert run(1.0, [1.0] * 4) == pytest.approx([0, 1, 2, 3])


def test_a_read_longer_than_the_interval_is_followed_at_once() -> None:
    """A start that is already late begins when the read before it ends."""
    assert run(1.0, [1.5] * 4) == pytest.approx([0, 1.5, 3, 4.5])


def test_a_stall_of_several_intervals_is_not_made_up_in_a_burst() -> None:
    """After a read that took 3.5 intervals the schedule goes on from the late start:
    the starts it missed (2, 3 and 4) are not run back to back."""
    starts = run(1.0, [0.1, 3.5, 0.1, 0.1, 0.1])
    assert starts == pytest.approx([0, 1, 4.5, 5.5, 6.5])
    assert min(gaps(starts)) == pytest.approx(1.0)


def test_an_interval_of_0_runs_back_to_back() -> None:
    assert run(0.0, [0.2, 0.3, 0.1]) == pytest.approx([0, 0.2, 0.5])


def test_the_start_stays_on_the_grid_when_asked_early() -> None:
    """Asked before the start is due, the schedule gives the due time, not a later one
    made of the time asked plus the interval."""
    schedule = Schedule()
    schedule.start(T0, 1.0)
    assert schedule.start(T0 + 0.3, 1.0) == pytest.approx(T0 + 1.0)
    assert schedule.start(T0 + 1.0, 1.0) == pytest.approx(T0 + 2.0)


def test_after_a_connection_failure_the_next_start_waits_the_backoff() -> None:
    """0.5 s after the failure, doubling while it goes on, however short the interval."""
    starts = run(0.1, [0.01] * 6, failing=frozenset(range(6)))
    ends = [start + 0.01 for start in starts]
    waits = [start - end for end, start in zip(ends, starts[1:], strict=False)]
    assert waits == pytest.approx([FIRST_DELAY, 1.0, 2.0, 4.0, MAX_DELAY])


def test_the_backoff_is_a_floor_not_added_to_the_interval() -> None:
    """With an interval longer than the backoff, a failed read keeps the schedule."""
    assert run(10.0, [0.01] * 3, failing=frozenset({0, 1})) == pytest.approx([0, 10, 20])


def test_a_read_after_the_controller_came_back_is_on_the_schedule_again() -> None:
    starts = run(0.1, [0.01] * 4, failing=frozenset({0}))
    assert starts == pytest.approx([0, 0.01 + FIRST_DELAY, 0.61, 0.71])
