"""The engine without a front end: lines in, events out, against the real simulator.

Each test drains the outbox as a front end does and waits on conditions with a deadline.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from rac_console.engine import Engine
from tests.support.drivers import Front
from tests.support.servers import RecordingServer


def test_starts_on_the_simulator_and_says_so(front: Front) -> None:
    front.until(lambda: front.status is not None, "the first status")
    assert front.status is not None
    assert front.status.is_simulator and front.status.target == "SIMULATOR (built-in)"
    front.until(
        lambda: front.status is not None and front.status.connection == "connected", "connected"
    )


def test_help_lists_every_command_and_explains_one(front: Front) -> None:
    (listing,) = front.run("help")
    for name in ("get", "put", "watch", "connect", "disconnect", "save", "load", "latency"):
        assert any(line.startswith(name) for line in listing.splitlines()), name
    (put,) = front.run("help put")
    assert put.startswith("put TYPE INDEX VALUE...") and "e.g. put I 10 123" in put
    assert front.run("help nosuch") == ["no command 'nosuch': type help for the list"]


def test_interval_sets_the_poll_period(front: Front) -> None:
    assert front.run("interval 0.2") == ["poll interval 0.2 s"]
    front.until(lambda: front.status is not None and front.status.interval == 0.2, "interval")
    assert front.errors("interval fast") == [
        "interval needs a number of seconds, e.g. interval 0.5, got 'fast'"
    ]
    front.run("watch I 1")
    front.until(lambda: front.sent().count(b"GET:RC8:1:I:\r") >= 3, "three polls")
    times = [f.time for f in front.frames if f.data == b"GET:RC8:1:I:\r"]
    assert times[2] - times[0] >= 2 * 0.2 * 0.95 - 0.01  # two periods between polls 1 and 3


def test_pause_stops_polling_and_resume_starts_it(front: Front) -> None:
    front.run("watch I 2")
    front.until(lambda: front.sent().count(b"GET:RC8:2:I:\r") >= 2, "polling")
    assert front.run("pause") == ["polling paused"]
    front.until(lambda: front.status is not None and front.status.paused, "the paused status")
    polls = front.sent().count(b"GET:RC8:2:I:\r")
    front.run("get S 1")  # a round trip: had a poll been due, it would have gone by now
    time.sleep(0.2)  # four poll periods with nothing due
    front.drain()
    assert front.sent().count(b"GET:RC8:2:I:\r") == polls
    assert front.run("resume") == ["polling resumed"]
    front.until(lambda: front.sent().count(b"GET:RC8:2:I:\r") > polls, "polls again")


def test_disconnect_then_connect(front: Front) -> None:
    front.run("watch I 3")
    front.until(lambda: front.rows.get("I3") is not None and front.rows["I3"].status == "OK", "OK")
    [said] = front.run("disconnect")
    assert said.startswith("disconnected: connect HOST[:PORT]") and "connect sim" in said
    front.until(lambda: front.rows["I3"].status == "DISCONNECTED", "the row marked")
    assert front.status is not None and front.status.target == "NOT CONNECTED"
    [error] = front.errors("get I 1")
    assert error.startswith("not connected: connect HOST[:PORT]") and "connect sim" in error
    server = RecordingServer(lambda line: b"0,3,77\r")
    try:
        assert front.run(f"connect 127.0.0.1:{server.port}") == [
            f"connected to LIVE controller 127.0.0.1:{server.port}"
        ]
        front.until(
            lambda: front.rows["I3"].variant is not None and front.rows["I3"].variant.value == 77,
            "the live value",
        )
        assert front.status is not None and front.status.target == f"LIVE 127.0.0.1:{server.port}"
        assert f"connected to 127.0.0.1:{server.port}" in front.notes
    finally:
        server.close()
    assert front.errors("connect 127.0.0.1:1")[0].startswith("cannot connect to 127.0.0.1:1")


def test_save_then_load_restores_the_watch_list(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "cell.toml"
    front.run('watch P 1 "pick" every 2')
    front.run("watch IO 4-5 gripper")
    assert front.run(f"save {path}") == [f"saved 3 watched variables to {path}"]
    front.run("unwatch all")
    front.until(lambda: not front.rows, "an empty table")
    assert front.run(f"load {path}") == [f"loaded 3 watched variables from {path}"]
    front.until(lambda: len(front.rows) == 3, "three rows")
    assert {k: (v.label, v.every) for k, v in front.rows.items()} == {
        "P1": ("pick", 2.0),
        "IO4": ("gripper", None),
        "IO5": ("gripper", None),
    }
    assert front.errors(f"load {tmp_path / 'missing.toml'}")[0].startswith("cannot read")


@pytest.mark.slow  # over half a second
def test_a_typed_command_waits_for_at_most_the_poll_in_flight() -> None:
    """50 rows polled back to back on a slow controller: a typed GET goes out right after
    the poll in flight, ahead of the 49 others of the cycle."""

    def slow(line: bytes) -> bytes:
        time.sleep(0.01)
        return b"0,3,1\r"

    server = RecordingServer(slow)
    engine = Engine("127.0.0.1", server.port, interval=0, timeout=2.0)
    engine.start()
    front = Front(engine)
    try:
        front.run("watch I 0-49")
        front.until(lambda: len(front.sent()) >= 60, "a cycle and more")
        front.drain()
        before = len(front.frames)
        seq = engine.submit("get S 9")
        front.until(lambda: seq in front.results, "the typed GET's answer")
        after = [f for f in front.frames[before:] if f.direction == "tx"]
        typed = next(n for n, frame in enumerate(after) if not frame.poll)
        assert after[typed].data == b"GET:RC8:9:S:\r"
        assert typed <= 1, [f.data for f in after[: typed + 1]]
    finally:
        engine.stop()
        server.close()


def test_stop_ends_a_latency_run_and_skips_queued_lines() -> None:
    """Quitting must not wait for a long latency run or for lines still queued behind a
    silent controller: when stop() returns, the engine has closed its target."""
    engine = Engine(None, interval=0.05, timeout=1.0)
    engine.start()
    front = Front(engine)
    seq = engine.submit("latency 100000 I 1")
    front.until(lambda: len(front.sent()) > 100, "the latency run to be under way")
    assert seq not in front.results
    engine.stop()
    front.drain()
    assert front.status is not None and not front.status.has_session

    silent = RecordingServer(lambda line: None)
    engine = Engine("127.0.0.1", silent.port, timeout=2.0)
    engine.start()
    try:
        for n in range(5):
            engine.submit(f"get I {n}")
        engine.stop()
        front = Front(engine)
        front.drain()
        assert front.status is not None and not front.status.has_session
    finally:
        silent.close()
