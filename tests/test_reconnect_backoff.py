"""A controller that drops every connection is not hammered: the poller backs off."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.engine.polling.backoff import (
    EARLY_EXCHANGES,
    FIRST_DELAY,
    GOOD_STRETCH,
    MAX_DELAY,
    Backoff,
)
from rac_console.tui.status_bar import StatusBar
from tests.support.drivers import log_text, make_app, type_line, until
from tests.support.servers import CLOSE, Answering, RecordingServer, fixed_reply

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow


def come_back(line: bytes) -> bytes:
    """A controller come back: it answers every request."""
    return b"0,3,1\r" if b":I:" in line else b"-2147024809\r"


def drop_after_one_request() -> tuple[RecordingServer, Answering]:
    """Accepts, reads one request, and closes without answering; with its reply's
    ``answer`` set to :func:`come_back`, it answers every request instead."""
    reply = Answering(CLOSE)
    return RecordingServer(reply), reply


def test_backoff_doubles_on_early_drops_and_resets_after_good_exchanges() -> None:
    backoff = Backoff()
    assert not backoff.closed()  # never connected: nothing dropped
    backoff.connected()
    assert backoff.closed()
    delays = [backoff.next_delay() for _ in range(6)]
    assert delays == [FIRST_DELAY, 1.0, 2.0, 4.0, MAX_DELAY, MAX_DELAY]
    backoff.connected()
    for _ in range(EARLY_EXCHANGES):
        backoff.good()
    assert not backoff.closed()  # it served: a drop now is not an early one
    backoff.connected()
    for _ in range(GOOD_STRETCH):
        backoff.good()
    assert backoff.next_delay() == FIRST_DELAY


async def test_a_controller_that_drops_every_connection_is_not_hammered(tmp_path: Path) -> None:
    server, reply = drop_after_one_request()
    try:
        app = make_app(tmp_path, "127.0.0.1", server.port, interval=0.05, timeout=1)
        async with app.run_test(size=(160, 40)) as pilot:
            status = app.query_one(StatusBar)
            await type_line(pilot, "watch I 0-49")
            await until(
                pilot,
                lambda: "waiting 4 s before the next try" in log_text(app),
                "the backoff to reach 4 s",
                timeout=15,
            )
            # One connection per try: 0.5, 1 and 2 s waits between the first four.
            assert server.accepted <= 5, server.accepted
            assert "waiting 2 s before the next try" in log_text(app)
            await until(
                pilot, lambda: "dropped early, retrying in" in str(status.render()), "countdown"
            )
            reply.answer = come_back  # the controller comes back: polling resumes
            await until(pilot, lambda: "polls/s" in str(status.render()), "polling again", 10)
            # A stretch of good exchanges resets the backoff: the next drop waits 0.5 s.
            first_waits = log_text(app).count(f"waiting {FIRST_DELAY:g} s before")
            reply.answer = CLOSE
            await until(
                pilot,
                lambda: log_text(app).count(f"waiting {FIRST_DELAY:g} s before") > first_waits,
                "a reset backoff",
                10,
            )
    finally:
        server.close()


def answer_once_then_close() -> RecordingServer:
    """Answers the first request of each connection, then closes it."""
    return RecordingServer(fixed_reply(b"0,3,1\r"), answers=1)


async def test_a_pause_during_a_backoff_leaves_no_countdown(tmp_path: Path) -> None:
    server, _ = drop_after_one_request()
    try:
        app = make_app(tmp_path, "127.0.0.1", server.port, interval=0.05, timeout=1)
        async with app.run_test(size=(160, 40)) as pilot:
            status = app.query_one(StatusBar)
            await type_line(pilot, "watch I 0-9")
            await until(pilot, lambda: "retrying in" in str(status.render()), "a countdown")
            await type_line(pilot, "pause")
            await until(pilot, lambda: "POLLING PAUSED" in str(status.render()), "paused")
            await until(pilot, lambda: "retrying" not in str(status.render()), "no countdown")
    finally:
        server.close()


def close_at_once() -> RecordingServer:
    """Accepts and closes at once, before reading anything."""
    return RecordingServer(fixed_reply(None), answers=0)


@pytest.mark.parametrize("server_kind", [answer_once_then_close, close_at_once])
async def test_other_controllers_that_keep_dropping_are_not_hammered(
    tmp_path: Path, server_kind: Callable[[], RecordingServer]
) -> None:
    server = server_kind()
    try:
        app = make_app(tmp_path, "127.0.0.1", server.port, interval=0.05, timeout=5)
        async with app.run_test(size=(160, 40)) as pilot:
            await type_line(pilot, "watch I 0-49")
            await until(
                pilot,
                lambda: "waiting 4 s before the next try" in log_text(app),
                "the backoff to reach 4 s",
                15,
            )
            assert len(server.peers) <= 6, len(server.peers)
    finally:
        server.close()
