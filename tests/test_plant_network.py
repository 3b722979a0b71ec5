"""Feeding the plant over a real network with a pulled cable.

Loopback never loses a packet, and a killed broker closes the connection at once; a
pulled cable does neither: nothing comes back, no FIN, no RST. Here, as in
``benchmarks/network_paths.py`` (whose namespaces this reuses), namespace A holds the
broker (mosquitto on A's address) and a subscriber, namespace B the watch with its
built-in simulator (polled over B's loopback, so polling never crosses the cable), and
``iptables -j DROP`` in A is the cable. With it out, polling goes on, the watch notices
the silence by its keepalive and says so once, and the broker, missing B's pings, sends
the feed's last will (``offline``); with it back, the feed reconnects, says so once and
publishes again. A change sent into the void before the loss was noticed is sent again
by paho after the reconnection, beside the latest value: the broker must be left with
the latest.

Needs root, ``ip``, ``iptables`` (as the benchmark checks) and mosquitto; skipped, with
the reason, where any is missing or the namespaces cannot be made.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests.support.brokers import Broker, mosquitto_path
from tests.support.drivers import RAC, Running
from tests.support.fixtures import needs_mosquitto

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmark's namespaces and cable, reused
from network_paths import SIM_HOST, Net, failure, why_not  # noqa: E402

#: Tens of seconds of real keepalives and reconnections: `pytest -m "not slow"` skips it.
pytestmark = [needs_mosquitto, pytest.mark.slow]

BROKER_HOST = SIM_HOST  # A's address on the veth
LISTENER = (sys.executable, str(Path(__file__).resolve().parent / "support" / "brokers.py"))
STATUS, I1 = "plant/sim/status", "plant/sim/I1"
LOST, BACK = "stopped answering (no reply to a ping in 15 s)", "the MQTT broker is back"
SIMULATOR = re.compile(r"built-in RC8 simulator.*\(at 127\.0\.0\.1:(\d+)\)")
#: Seconds for anything that takes no network timeout (a start, lines of a 0.1 s watch).
QUICK = 60.0
#: Seconds for what waits on the keepalive (15 s: paho gives up after up to twice that,
#: the broker after 1.5 times) or on the reconnection's backoff (at most 30 s, plus a
#: connection attempt's own 5 s timeout), with room to spare on a busy machine.
SLOW = 120.0


@pytest.fixture
def net() -> Iterator[Net]:
    reason = why_not()
    if reason is not None:
        pytest.skip(reason)
    made = Net(f"m{os.getpid()}")
    try:
        try:
            made.up()
        except (subprocess.SubprocessError, OSError) as exc:
            pytest.skip(f"cannot make network namespaces: {failure(exc)}")
        yield made
    finally:
        made.down()  # kills what is left in them too


def received(listener: Running) -> list[tuple[str, str]]:
    """The messages the subscriber printed so far, in order: (topic, payload)."""
    lines = (json.loads(line) for line in listener.out)
    return [(line["topic"], line["payload"]) for line in lines if "topic" in line]


def arrives(
    listener: Running, after: int, *wanted: tuple[str, Callable[[str], bool]]
) -> Callable[[], bool]:
    """A condition: each (topic, test of its payload) in ``wanted`` came after the
    first ``after`` messages."""

    def holds() -> bool:
        since = received(listener)[after:]
        return all(
            any(topic == want and test(payload) for topic, payload in since)
            for want, test in wanted
        )

    return holds


def is_text(expected: str) -> Callable[[str], bool]:
    return lambda payload: payload == expected


def value_is(expected: object) -> Callable[[str], bool]:
    def test(payload: str) -> bool:
        return payload.startswith("{") and json.loads(payload)["value"] == expected

    return test


def said(watch: Running, text: str) -> int:
    return sum(text in line for line in watch.err)


def simulator_port(watch: Running) -> int:
    """The port of the watch's built-in simulator, on B's loopback (as it says)."""
    watch.wait_for("the simulator's address", lambda: any(SIMULATOR.search(e) for e in watch.err))
    return next(int(m.group(1)) for e in watch.err if (m := SIMULATOR.search(e)))


def put(env: dict[str, str], net: Net, port: int, value: int) -> None:
    """I1 = ``value`` on the watch's simulator, from B (the cable is not in the way)."""
    done = subprocess.run(
        net.in_b(*RAC, "-H", "127.0.0.1", "-p", str(port), "--json", "put", "I", "1", str(value)),
        env=env,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=QUICK,
    )
    assert done.returncode == 0 and json.loads(done.stdout)["verified"], done


def shows(watch: Running, value: int) -> Callable[[], bool]:
    """A condition: the watch's last line shows I1 = ``value``."""
    return lambda: bool(watch.out) and json.loads(watch.out[-1])["values"].get("I1") == value


def test_a_pulled_cable_sends_the_last_will_and_the_feed_comes_back_with_the_cable(
    env: dict[str, str], net: Net, running: list[Running], tmp_path: Path
) -> None:
    # The broker in A, on A's address, with the configuration the other tests use.
    broker = Broker(tmp_path, host=BROKER_HOST)
    mosquitto = mosquitto_path()
    assert mosquitto is not None
    log = tmp_path / "mosquitto.log"
    with log.open("ab") as out:
        process = subprocess.Popen(
            net.in_a(mosquitto, "-c", str(broker.write_config())),
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    try:
        # A subscriber in A, which the cable never separates from the broker.
        listener = Running(
            env, BROKER_HOST, str(broker.port), "plant/#", wrap=net.in_a(), program=LISTENER
        )
        running.append(listener)
        listener.wait_for(
            "the subscriber connected (the broker listening)",
            lambda: (
                process.poll() is not None or any('"connected"' in line for line in listener.out)
            ),
            QUICK,
        )
        assert process.poll() is None, f"mosquitto ended: {log.read_text()}"

        # The watch in B: the built-in simulator, polled over B's loopback.
        watch = Running(
            env, "--json", "watch", "I", "1", "--every", "0.1",
            "--mqtt", f"{broker.url}/plant", wrap=net.in_b(),
        )  # fmt: skip
        running.append(watch)
        listener.wait_for(
            "online and the first value",
            arrives(listener, 0, (STATUS, is_text("online")), (I1, value_is(1))),
            QUICK,
        )
        # Said on stderr, which the test reads apart from the listener: not yet, maybe.
        watch.wait_for(
            "publishing said", lambda: said(watch, "publishing sim's watched values to") >= 1, QUICK
        )

        simulator = simulator_port(watch)

        # The cable out: polling goes on, a change polled is handed to the feed (which
        # sends it into the void: nothing has told it yet); the watch's keepalive
        # notices, once; the broker, missing its pings, sends the last will, seen in A.
        before_pull = len(received(listener))
        net.pull()
        put(env, net, simulator, 2)
        watch.wait_for("the change polled, cable out", shows(watch, 2), QUICK)
        lines = len(watch.out)
        watch.wait_for("20 more lines, cable out", lambda: len(watch.out) >= lines + 20, QUICK)
        listener.wait_for(
            "the last will, offline",
            arrives(listener, before_pull, (STATUS, is_text("offline"))),
            SLOW,
        )
        watch.wait_for("the loss said", lambda: said(watch, LOST) >= 1, SLOW)
        put(env, net, simulator, 3)  # changed again while the feed knows the broker away
        watch.wait_for("the second change polled", shows(watch, 3), QUICK)
        lines = len(watch.out)
        watch.wait_for("20 more lines after the loss", lambda: len(watch.out) >= lines + 20, QUICK)
        assert said(watch, BACK) == 0
        assert received(listener)[before_pull:] == [(STATUS, "offline")]

        # The cable back: the feed reconnects, says so once, and publishes the latest.
        before_restore = len(received(listener))
        net.restore()
        watch.wait_for("the return said", lambda: said(watch, BACK) >= 1, SLOW)
        listener.wait_for(
            "online again and the latest value published",
            arrives(listener, before_restore, (STATUS, is_text("online")), (I1, value_is(3))),
            SLOW,
        )

        # A clean end: exit 0, and the feed says offline itself, after everything else
        # it sent on that connection (the broker takes them in order).
        before_stop = len(received(listener))
        assert watch.stop() == 0, watch.err
        listener.wait_for(
            "offline at the clean end",
            arrives(listener, before_stop, (STATUS, is_text("offline"))),
            QUICK,
        )
        values = [
            json.loads(payload)["value"] for topic, payload in received(listener) if topic == I1
        ]
        assert values[-1] == 3, f"the plant is left with I1 = {values[-1]} (all sent: {values})"
        reports = [json.loads(line) for line in watch.out]
        assert all(r["ok"] and r["values"]["I1"] in (1, 2, 3) for r in reports), reports
        assert said(watch, LOST) == 1, watch.err
        assert said(watch, BACK) == 1, watch.err
        assert said(watch, "Traceback") == 0, watch.err
        assert said(watch, "publishing sim's watched values to") == 1, watch.err
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(20)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(20)


def test_a_black_holed_broker_address_is_said_to_give_no_answer(
    env: dict[str, str], net: Net, running: list[Running]
) -> None:
    """Nothing comes back from the broker's address (its packets dropped): not "is it
    an MQTT port?", which is for a port that answers in something else."""
    net.pull()
    watch = Running(
        env, "--json", "watch", "I", "1", "--every", "0.1",
        "--mqtt", f"mqtt://{BROKER_HOST}:1883/plant", wrap=net.in_b(),
    )  # fmt: skip
    running.append(watch)
    watch.wait_for("the silence said", lambda: said(watch, "MQTT") >= 1, SLOW)
    lines = len(watch.out)
    watch.wait_for("polling on", lambda: len(watch.out) >= lines + 20, QUICK)
    assert watch.stop() == 0, watch.err
    mqtt = [line for line in watch.err if "MQTT" in line]
    assert len(mqtt) == 1, watch.err
    assert f"no answer from the MQTT broker {BROKER_HOST}:1883 within 5 s" in mqtt[0]
    assert "is it an MQTT port" not in mqtt[0]
