"""A served session's poll load is bounded by default: at least ``--min-interval``
seconds between polls of a row, at most ``--max-rows`` rows per target, each set on the
``serve`` line. Judged from the controller's side: the variables a recording controller
is asked for and how many GETs reach it, from a session that asks for 4,096 rows polled
back to back."""

from __future__ import annotations

import time

import pytest

from rac_console.engine import Engine
from rac_console.engine.setup.poll_bounds import (
    MAX_ROWS_ENV,
    MIN_INTERVAL_ENV,
    SERVED_MAX_ROWS,
    SERVED_MIN_INTERVAL,
    UNBOUNDED,
    PollBounds,
    bounds_for,
)
from rac_console.engine.setup.where import Where
from tests.support.drivers import Front
from tests.support.servers import RecordingServer
from tests.support.serving import consoles_of, open_console, start_serve, until

#: What the session is refused, with the bound and how the operator changes it.
ROWS_REFUSED = "a served console watches at most {} rows per target"
INTERVAL_REFUSED = "faster than a served console may poll: at least {:g} s"


def asked(controller: RecordingServer, since: int = 0) -> list[bytes]:
    """The GETs the controller got after its first ``since`` lines."""
    return [line for line in controller.lines[since:] if line.startswith(b"GET:")]


@pytest.mark.slow
def test_a_served_session_asking_for_4096_rows_back_to_back_stays_within_the_bounds(
    env, running, recording
) -> None:
    pytest.importorskip("textual_serve", reason="needs the extra web")
    controller = recording()
    served = start_serve(env, running, before=("-H", f"127.0.0.1:{controller.port}"))
    console = open_console(served, 160, 50)
    console.until("SERVED", "connected")
    for first in range(0, 4096, 256):  # each line answered before the next, as typed
        console.type_line(f"watch I {first}-{first + 255}")
        console.until(f"› watch I {first}-{first + 255}")
    console.type_line("interval 0")
    shown = console.until(
        ROWS_REFUSED.format(SERVED_MAX_ROWS), INTERVAL_REFUSED.format(SERVED_MIN_INTERVAL)
    )
    assert "rac-console serve --max-rows N" in shown
    assert "rac-console serve --min-interval SECONDS" in shown
    # Every row the session holds has been polled twice: polling is in its stride.
    until(
        lambda: min(asked(controller).count(f"GET:RC8:{i}:I:".encode()) for i in range(256)) >= 2,
        "two polls of each of the first 256 rows",
        deadline=60,
    )
    started, since = time.monotonic(), len(controller.lines)
    until(lambda: time.monotonic() - started >= 2.0, "two seconds of polling")
    polls, window = asked(controller, since), time.monotonic() - started
    console.close()
    until(lambda: consoles_of(served.running.process.pid) == [], "the console ending")
    every_row = set(asked(controller))
    assert len(every_row) == SERVED_MAX_ROWS, f"{len(every_row)} rows polled"
    # A row is polled at most once a floor (a cycle may start 5 % early), and a cycle
    # sent just before the window may be recorded in it: one cycle more at most.
    most = SERVED_MAX_ROWS * (window / (0.95 * SERVED_MIN_INTERVAL) + 2)
    assert len(polls) <= most, f"{len(polls)} GETs in {window:.1f} s ({len(polls) / window:.0f}/s)"


@pytest.mark.slow
def test_the_operator_sets_the_bounds_on_the_serve_line(env, running, recording) -> None:
    pytest.importorskip("textual_serve", reason="needs the extra web")
    controller = recording()
    served = start_serve(
        env,
        running,
        "--min-interval",
        "0.1",
        "--max-rows",
        "3",
        before=("-H", f"127.0.0.1:{controller.port}"),
    )
    console = open_console(served)
    console.until("SERVED", "connected")
    console.type_line("watch I 0-3")
    console.until(ROWS_REFUSED.format(3), "(0 now")
    console.type_line("watch I 0-2")
    console.until("watching I0..I2")
    console.type_line("interval 0.05")
    console.until(INTERVAL_REFUSED.format(0.1))
    console.type_line("interval 0.1")
    console.until("poll interval 0.1 s")
    console.close()
    until(lambda: consoles_of(served.running.process.pid) == [], "the console ending")
    assert {line.split(b":")[2] for line in asked(controller)} == {b"0", b"1", b"2"}


def test_the_poller_asks_the_bounds_before_it_changes() -> None:
    """Every way of adding rows or changing the pace is bounded, and a refusal changes
    nothing; without bounds (anywhere but a served console) anything goes."""
    engine = Engine(None, interval=0.05, timeout=1.0, bounds=PollBounds(0.2, 3))
    engine.start()
    try:
        front = Front(engine)
        front.until(lambda: front.status is not None, "a status")
        assert front.status is not None and front.status.interval == 0.2  # the floor
        assert front.errors("watch I 0-3") == [
            "4 more rows would make 4: a served console watches at most 3 rows per target "
            "(0 now; the operator sets it: rac-console serve --max-rows N)"
        ]
        assert front.errors("watch I 0-1") == []
        assert front.errors("watch I 1-2") == []  # one new row: three in all
        assert front.errors("watch I 3") != []
        assert front.errors("watch I 0 every 0.1") == [
            "every 0.1 is faster than a served console may poll: at least 0.2 s "
            "(the operator sets it: rac-console serve --min-interval SECONDS)"
        ]
        assert front.errors("interval 0") != [] and front.errors("interval 0.3") == []
        front.until(lambda: set(front.rows) == {"I0", "I1", "I2"}, "three rows")
        assert front.rows["I0"].every is None  # the refused every changed nothing
    finally:
        engine.stop()
    unbounded = Engine(None, interval=0.05, timeout=1.0)
    unbounded.start()
    try:
        front = Front(unbounded)
        assert front.errors("watch I 0-255") == [] and front.errors("watch I 256-511") == []
        assert front.errors("interval 0") == [] and front.errors("watch I 0 every 0") == []
    finally:
        unbounded.stop()


def test_a_served_console_takes_its_bounds_from_serve_and_keeps_them_whatever_comes() -> None:
    served = {MIN_INTERVAL_ENV: "0.1", MAX_ROWS_ENV: "3"}
    assert bounds_for(Where.SERVED, served) == PollBounds(0.1, 3)
    default = PollBounds(SERVED_MIN_INTERVAL, SERVED_MAX_ROWS)
    assert bounds_for(Where.SERVED, {}) == default
    for junk in ("", "x", "-1", "nan", "inf", "1e400"):
        assert bounds_for(Where.SERVED, {MIN_INTERVAL_ENV: junk, MAX_ROWS_ENV: junk}) == default
    assert bounds_for(Where.CONSOLE, served) == UNBOUNDED
