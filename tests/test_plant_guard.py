"""A broker that lies: what it sends cannot take the watch's memory or its polling.

The brokers are the tests' own (``tests/support/brokers.py``, 127.0.0.1, port 0): each reads
the CONNECT, then does one hostile thing until the client hangs up: a CONNACK announcing
256 MB followed by an endless stream, a CONNACK followed by junk, a CONNACK followed by
silence, a CONNACK followed by a storm of acknowledgements. The watch is the real CLI;
its peak memory is the kernel's (``VmHWM``), what it did is judged at the broker (which
connections came, when, and whether the client hung up), and polling is judged by the
lines the watch printed after the broker began.
"""

from __future__ import annotations

import inspect
import json
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rac_console.plant.mqtt_guard import (
    MOST_PACKET,
    BrokerMisbehaved,
    InboundGuard,
)
from tests.support.brokers import CONNACK, HOSTILE, HUGE_CONNACK, HostileBroker, hostile_broker
from tests.support.drivers import Running

#: What the watch says of each, in its one line.
SAYS = {
    "a 256 MB CONNACK": "broke the protocol (it announced a CONNACK of 268,435,455 bytes",
    "a CONNACK, then junk": "broke the protocol (it sent ",
    "a CONNACK, then a PUBACK storm": "broke the protocol (it acknowledged ",
    "a CONNACK, then silence": "stopped answering (no reply to a ping in 2 s)",
    "a CONNACK, then a packet dripped": "broke the protocol (it took over 2 s to send one PUBACK",
    "an ack, then a PUBLISH never asked for": "broke the protocol (it sent a PUBLISH",
}
#: The watch's peak resident memory, at most (it is about 40 MB at rest).
MOST_RSS_MB = 150


# ------------------------------------------------------------------ the guard alone


def guard(sent: int = 0, clock: Callable[[], float] = lambda: 0.0) -> InboundGuard:
    return InboundGuard(lambda: sent, keepalive=15, clock=clock)


def test_an_honest_brokers_answers_pass_byte_by_byte_and_whole() -> None:
    stream = CONNACK + bytes((0x40, 2, 0, 1)) + bytes((0x40, 3, 0, 2, 0)) + bytes((0xD0, 0))
    one = guard(sent=2)
    one.pinged()
    for byte in stream:
        one.take(bytes((byte,)))
    whole = guard(sent=2)
    whole.pinged()
    whole.take(stream)
    assert one.broke is None


def test_a_packet_longer_than_announced_is_refused_at_its_length() -> None:
    one = guard()
    with pytest.raises(BrokerMisbehaved, match="268,435,455 bytes"):
        one.take(HUGE_CONNACK)
    assert one.broke is not None and not one.broke.first
    at_most = guard()
    at_most.take(bytes((0x20, 0x80, 0x80, 0x04)))  # 65,536: the most, taken
    with pytest.raises(BrokerMisbehaved, match="65,537 bytes"):
        guard().take(bytes((0x20, 0x81, 0x80, 0x04)))
    assert MOST_PACKET == 65_536


@pytest.mark.parametrize(
    ("stream", "says", "first"),
    [
        (b"HTTP/1.1 400 Bad Request\r\n", "first answer is not an MQTT CONNACK", True),
        (CONNACK + bytes((0x30, 2, 0, 0)), "a PUBLISH", False),
        (CONNACK + CONNACK, "a second CONNACK", False),
        (CONNACK + bytes((0x42, 2, 0, 1)), "a PUBACK", False),  # flags must be 0
        (CONNACK + bytes((0x40, 0xFF, 0xFF, 0xFF, 0xFF)), "more than 4 bytes", False),
        (CONNACK + bytes((0x40, 2, 0, 1)) * 4, "acknowledged 4 messages, 3 were sent", False),
    ],
)
def test_what_no_broker_sends_a_publisher_is_refused(stream: bytes, says: str, first: bool) -> None:
    one = guard(sent=3)
    with pytest.raises(BrokerMisbehaved, match=says) as raised:
        one.take(stream)
    assert raised.value.first is first


def test_pings_are_answered_no_more_often_than_they_are_sent() -> None:
    """Counted against the pings that went out: a broker that shortens the keepalive in
    its CONNACK makes paho ping more often, and its answers are all honest."""
    one = guard()
    one.take(CONNACK)
    for _ in range(12):
        one.pinged()
    one.take(bytes((0xD0, 0)) * 12)
    with pytest.raises(BrokerMisbehaved, match="pings"):
        one.take(bytes((0xD0, 0)))


def test_an_acknowledgement_cut_by_a_lost_connection_is_not_counted() -> None:
    """The connection went after the first byte of a PUBACK: paho sends the message
    again and the broker acknowledges it again: one acknowledgement, not two."""
    one = guard(sent=3)
    one.take(CONNACK + bytes((0x40, 2, 0, 1)) + bytes((0x40,)))  # the second ack cut
    one.new_connection()
    one.take(CONNACK + bytes((0x40, 2, 0, 2)) + bytes((0x40, 2, 0, 3)))
    assert one.broke is None


def test_a_packet_dripped_slower_than_a_keepalive_is_refused() -> None:
    now = [0.0]
    one = guard(sent=5, clock=lambda: now[0])
    one.take(CONNACK + bytes((0x40, 0x80, 0x80, 0x04)) + b"x")  # 64 KiB announced
    now[0] = 10.0
    one.take(b"x")  # within the keepalive (15 s)
    now[0] = 15.5
    with pytest.raises(BrokerMisbehaved, match="took over 15 s to send one PUBACK"):
        one.take(b"x")


def test_the_private_parts_of_paho_the_hooks_override_are_still_there() -> None:
    """paho has no public hook for these: when an upgrade moves one, this fails (and
    pyproject's pin says which versions were checked)."""
    import paho.mqtt.client as mqtt
    from paho.mqtt.enums import CallbackAPIVersion

    from rac_console.plant.paho_hooks import PRIVATE

    client = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
    for name in PRIVATE:
        assert hasattr(client, name), name
    assert list(inspect.signature(client._sock_recv).parameters) == ["bufsize"]
    assert list(inspect.signature(client._ssl_wrap_socket).parameters) == ["tcp_sock"]
    assert hasattr(mqtt._ConnectionState, "MQTT_CS_DISCONNECTING")  # type: ignore[attr-defined]
    reads = inspect.getsource(mqtt.Client._packet_read)
    assert "self._sock_recv(" in reads and ".recv(" not in reads.replace("_sock_recv(", "")


# ------------------------------------------------------------------ hostile brokers


@pytest.fixture
def hostile(request: pytest.FixtureRequest) -> Iterator[HostileBroker]:
    broker = hostile_broker(request.param)
    try:
        yield broker
    finally:
        broker.close()


def peak_rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    raise AssertionError("no VmHWM")


def mqtt_lines(watch: Running) -> list[str]:
    return [line for line in watch.err if "MQTT" in line]


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads the peak RSS in /proc")
@pytest.mark.parametrize("hostile", list(HOSTILE), indirect=True)
def test_a_hostile_broker_is_dropped_in_one_line_and_cannot_take_memory_or_polling(
    hostile: HostileBroker, env: dict[str, str], running: list[Running], tmp_path: Path
) -> None:
    config = tmp_path / "rac.toml"
    config.write_text("[mqtt]\nkeepalive = 2\n")  # the silent broker is found out in 4 s
    watch = Running(
        env | {"RAC_CONSOLE_CONFIG": str(config)},
        "--json", "watch", "I", "1", "--every", "0.05",
        "--mqtt", f"mqtt://127.0.0.1:{hostile.port}/plant",
    )  # fmt: skip
    running.append(watch)
    # Dropped, and tried again after a wait (1 s), and again after a longer one (2 s).
    watch.wait_for("three connections", lambda: hostile.count()[0] >= 3, deadline=60)
    lines_then = len(watch.out)
    watch.wait_for("polling after them", lambda: len(watch.out) >= lines_then + 20, deadline=60)
    peak = peak_rss_mb(watch.process.pid)
    times = hostile.connections[:3]
    assert watch.stop() == 0
    assert peak < MOST_RSS_MB, f"peak RSS {peak:.0f} MB"
    assert times[2] - times[1] >= 1.9, "the second wait is no longer than the first"
    assert hostile.count()[1] >= 2, "the client did not hang up on the hostile broker"
    said = mqtt_lines(watch)
    trouble = [line for line in said if "the MQTT broker is back:" not in line]
    assert len(trouble) == 1, watch.err  # and "back" once at most: it took a message
    assert len(said) <= 2, watch.err
    assert SAYS[hostile.name] in trouble[0]
    assert "Traceback" not in "\n".join(watch.err)
    values = [json.loads(line)["values"]["I1"] for line in watch.out if line.startswith("{")]
    assert len(values) >= 20


@pytest.mark.slow
def test_an_honest_broker_that_shortens_the_keepalive_is_kept(
    env: dict[str, str], running: list[Running], tmp_path: Path
) -> None:
    """Its CONNACK says ping every second (Server Keep Alive): paho does, and every
    answer is to a ping that went out. Nothing is said, the connection stays."""
    broker = hostile_broker("honest, with a 1 s Server Keep Alive")
    try:
        config = tmp_path / "rac.toml"
        config.write_text("[mqtt]\nkeepalive = 60\n")
        watch = Running(
            env | {"RAC_CONSOLE_CONFIG": str(config)},
            "--json", "watch", "I", "1", "--every", "0.05",
            "--mqtt", f"mqtt://127.0.0.1:{broker.port}/plant",
        )  # fmt: skip
        running.append(watch)
        watch.wait_for("six pings answered", lambda: broker.pings >= 6, deadline=60)
        assert watch.stop() == 0
    finally:
        broker.close()
    assert broker.count()[0] == 1, "the client hung up on an honest broker"
    assert mqtt_lines(watch) == [], watch.err
