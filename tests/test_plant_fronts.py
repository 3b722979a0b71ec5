"""``publish`` typed at the console and the REPL, against a real mosquitto: started,
asked where, stopped; on a cell, one line publishes every target and ``@NAME`` one."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import sys
from pathlib import Path

import pytest

from rac_console.sim.cell import SimulatedCellThread
from tests.support.brokers import Broker, Subscriber
from tests.support.cells import make_cell_app
from tests.support.drivers import Driver, Terminal, make_app, results_text, type_line, until
from tests.support.fixtures import needs_mosquitto

pytestmark = [needs_mosquitto, pytest.mark.slow]
QUICK = {"cycle": 0.8, "hold": 0.4, "reaction": 0.1}


# A subscriber's wait blocks: it runs on a thread, the console's loop goes on.


def status_is(topic: str, state: bytes):
    return lambda s: s.last.get(topic) == state


async def test_publish_in_the_repl_starts_says_where_and_stops(
    tmp_path: Path, broker: Broker, subscriber: Subscriber
) -> None:
    driver = Driver(tmp_path)
    url = f"{broker.url}/plant"

    async def steps(d: Driver) -> None:
        d.type(f"publish {url}\r")
        await d.until(lambda out: "publishing sim's watched values" in out, "publishing")
        d.type("watch I 1\r")  # the REPL's watch: published while it is shown
        await asyncio.to_thread(subscriber.wait_for, "I1", subscriber.has_value("plant/sim/I1", 1))
        d.type("\r")  # back to the prompt
        await d.until(lambda out: not d.repl.rows, "the watch to end")
        # Unwatched: the retained topic says so, no value left to be read as live.
        await asyncio.to_thread(
            subscriber.wait_for,
            "I1 unwatched",
            lambda s: b'"UNWATCHED"' in s.last.get("plant/sim/I1", b""),
        )
        assert json.loads(subscriber.last["plant/sim/I1"])["value"] is None
        d.type("publish\r")
        await d.until(lambda out: "sim's watched values go to mqtt://" in out, "where")
        d.type("publish off\r")
        await d.until(lambda out: "stopped publishing sim's values" in out, "stopped")
        await asyncio.to_thread(
            subscriber.wait_for, "offline", status_is("plant/sim/status", b"offline")
        )
        d.type("publish mqtt://broker\r")  # refused, and said how to write it
        await d.until(lambda out: "give a topic prefix" in out, "the refusal")

    await driver.run(steps)


async def test_publish_on_a_cell_feeds_every_target_and_at_name_one(
    tmp_path: Path, broker: Broker, subscriber: Subscriber
) -> None:
    with SimulatedCellThread(2, **QUICK) as sims:
        app = make_cell_app(tmp_path, sims)
        async with app.run_test(size=(120, 40)) as pilot:
            await type_line(pilot, "@robotA watch IO 128 part placed")
            await type_line(pilot, "@robotB watch IO 64 go")
            await type_line(pilot, f"publish {broker.url}/plant")
            await until(
                pilot,
                lambda: "publishing robotB's" in results_text(app),
                "one answer naming both targets",
            )
            said = results_text(app)
            assert "publishing robotA's watched values" in said
            # The handshake, as the plant sees it: both targets' topics, both values moving.
            a_seen: set[object] = set()
            b_seen: set[object] = set()

            def moved(s: Subscriber) -> bool:
                for topic, seen in (("plant/robotA/IO128", a_seen), ("plant/robotB/IO64", b_seen)):
                    if topic in s.last:
                        seen.add(json.loads(s.last[topic])["value"])
                return len(a_seen) == 2 and len(b_seen) == 2

            await asyncio.to_thread(subscriber.wait_for, "both handshake values moving", moved)
            label = json.loads(subscriber.last["plant/robotA/IO128"])["label"]
            assert label == "part placed"
            await type_line(pilot, "@robotB publish off")
            await asyncio.to_thread(
                subscriber.wait_for, "robotB offline", status_is("plant/robotB/status", b"offline")
            )
            assert subscriber.last["plant/robotA/status"] == b"online"
            await until(pilot, lambda: "stopped publishing robotB's" in results_text(app), "off")
        await asyncio.to_thread(
            subscriber.wait_for,
            "robotA offline at the end",
            status_is("plant/robotA/status", b"offline"),
        )


async def test_the_status_line_says_where_the_values_go_and_when_the_broker_is_lost(
    tmp_path: Path, broker: Broker, subscriber: Subscriber
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await type_line(pilot, "watch I 1")
        assert "MQTT" not in app.main_screen.panes.status_bar.line.plain
        await type_line(pilot, f"publish {broker.url}/plant")
        await until(
            pilot, lambda: "MQTT" in app.main_screen.panes.status_bar.line.plain, "the MQTT badge"
        )
        await asyncio.to_thread(subscriber.wait_for, "I1", subscriber.has_value("plant/sim/I1", 1))
        assert " MQTT " in app.main_screen.panes.status_bar.line.plain  # connected
        broker.stop()  # the badge must not go on looking healthy
        await until(
            pilot, lambda: "MQTT LOST" in app.main_screen.panes.status_bar.line.plain, "MQTT LOST"
        )
        broker.start()
        await until(
            pilot,
            lambda: (
                "MQTT LOST" not in app.main_screen.panes.status_bar.line.plain
                and " MQTT " in app.main_screen.panes.status_bar.line.plain
            ),
            "the broker back",
        )
        await type_line(pilot, "publish off")
        await until(
            pilot,
            lambda: "MQTT" not in app.main_screen.panes.status_bar.line.plain,
            "the badge gone",
        )


def test_the_last_will_says_offline_when_the_console_is_killed(
    terminal: Terminal,
    broker: Broker,
    subscriber: Subscriber,
) -> None:
    """The full-screen console in a real terminal, publishing, then killed outright."""
    command = f"{sys.executable} -m rac_console --mqtt {broker.url}/plant"
    terminal.tmux("new-session", "-d", "-s", "t", "-x", "120", "-y", "40", command)
    terminal.until("type help")
    terminal.tmux("send-keys", "-t", "t", "watch I 1", "Enter")
    terminal.until(" MQTT ")  # the status line says where the values go
    subscriber.wait_for("I1", subscriber.has_value("plant/sim/I1", 1))
    subscriber.wait_for("online", status_is("plant/sim/status", b"online"))
    console = int(terminal.tmux("list-panes", "-t", "t", "-F", "#{pane_pid}").split()[0])
    os.kill(console, signal.SIGKILL)  # no clean end: only the broker can say it
    subscriber.wait_for("the last will", status_is("plant/sim/status", b"offline"))


async def test_a_password_typed_in_a_publish_line_is_refused_and_kept_nowhere(
    tmp_path: Path,
) -> None:
    """A base64 password holds /: the address is refused without being repeated, the
    line is not kept in the history, and nothing is published anywhere."""
    driver = Driver(tmp_path)
    typed = "publish mqtt://rac:4711/s3cret@127.0.0.1:1883/line2"

    async def steps(d: Driver) -> None:
        d.type(f"{typed}\r")
        await d.until(lambda out: "no user or password" in out, "the refusal")
        d.type("get I 1\r")  # a line after it, kept: the history is written by now
        await d.until(lambda out: "I1 = " in out, "the next line")

    out = await driver.run(steps)
    assert "s3cret" not in out and "4711" not in out
    assert "publishing" not in out
    history = (tmp_path / "history").read_text(encoding="utf-8")
    assert "get I 1" in history and "s3cret" not in history


def test_every_state_of_the_feed_has_a_badge_and_trouble_looks_like_trouble() -> None:
    from rac_console.plant.mqtt import STATES, TROUBLE
    from rac_console.present.status import ALARM_STYLE, MQTT_BADGES

    assert set(MQTT_BADGES) == set(STATES)
    for state in TROUBLE:
        assert MQTT_BADGES[state][1] is ALARM_STYLE, state


async def test_a_broker_that_breaks_the_protocol_turns_the_badge_red(tmp_path: Path) -> None:
    from tests.support.brokers import hostile_broker

    hostile = hostile_broker("a 256 MB CONNACK")
    app = make_app(tmp_path)
    try:
        async with app.run_test(size=(120, 40)) as pilot:
            await type_line(pilot, "watch I 1")
            await type_line(pilot, f"publish mqtt://127.0.0.1:{hostile.port}/plant")
            await until(
                pilot,
                lambda: "MQTT BROKEN" in app.main_screen.panes.status_bar.line.plain,
                "the MQTT BROKEN badge",
            )
            await until(pilot, lambda: "broke the protocol" in results_text(app), "the one line")
            await type_line(pilot, "publish off")
    finally:
        hostile.close()
