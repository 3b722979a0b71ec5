"""The agent's clients get the engine's events as the engine made them: every kind of
event a real engine publishes, packed and unpacked, is equal to itself; bytes naming a
class that does not travel are refused, never made."""

from __future__ import annotations

import dataclasses
import socket
from typing import Any

import msgpack
import pytest

from rac_console.agent import codec
from rac_console.engine import Batch, Engine
from tests.support.drivers import Front

LINES = (
    "watch I 1-3 P 1 J 1 T 1 V 1 S 1 F 1 D 1 IO 128",
    "get I 1",
    "put I 1 5",
    "put P 2 1 2 3 4 5 6 7",
    "put S 3 'a b'",
    "send GET:RC8:10:I:",
    "send GET:RC8:10:Q:",
    "get I 99999999",
    "wait I 1 = 5 for 2",
    "latency 5",
    "help",
    "pause",
    "resume",
    "unwatch I 2",
    "interval 0.2",
)


def same(before: Any, after: Any) -> None:
    """Equal, or for an exception: the same class, args and attributes."""
    if isinstance(before, BaseException):
        assert type(after) is type(before)
        assert after.args == before.args
        assert vars(after) == vars(before)
    elif dataclasses.is_dataclass(before) and not isinstance(before, type):
        assert type(after) is type(before)
        for field in dataclasses.fields(before):
            same(getattr(before, field.name), getattr(after, field.name))
    elif isinstance(before, (list, tuple)):
        assert type(after) is type(before) and len(after) == len(before)
        for b, a in zip(before, after, strict=True):
            same(b, a)
    else:
        assert after == before, (before, after)
        assert type(after) is type(before)


class Packing(Front):
    """A front end that packs every batch before it reads it, and counts the kinds."""

    def __init__(self, engine: Engine) -> None:
        super().__init__(engine)
        self.kinds: set[str] = set()

    def drain(self) -> None:
        batch = self.engine.outbox.drain()
        for event in batch.events:
            self.kinds.add(type(event).__name__)
            for part in getattr(event, "feedback", ()):
                self.kinds.add(type(part).__name__)
                failure = getattr(part, "failure", None)
                if failure is not None:
                    self.kinds.add(type(failure).__name__)
        whole = [batch.events, batch.rows, batch.removed, batch.status]
        unpacked = codec.unpack(codec.pack(whole))
        same(whole[0], unpacked[0])
        assert unpacked[1] == batch.rows and unpacked[2] == batch.removed
        assert unpacked[3] == batch.status
        events, rows, removed, status = unpacked
        self.read(
            "engine",
            Batch(events, rows, removed, status, batch.frames_dropped, batch.cycles_dropped),
        )


def test_every_event_of_a_working_engine_comes_back_equal() -> None:
    engine = Engine(None, interval=0.05, timeout=2.0, cycles=True)
    engine.start()
    try:
        front = Packing(engine)
        for line in LINES:
            front.run(line)
        front.until(lambda: "P1" in front.rows and front.rows["P1"].status == "OK", "P1 read")
    finally:
        engine.stop()
    assert {"Result", "Outcome", "Cycle", "Frame"} <= front.kinds, front.kinds


def test_the_outcomes_of_an_unreachable_controller_come_back_equal() -> None:
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    engine = Engine("127.0.0.1", port, interval=0.05, timeout=1.0)
    engine.start()
    try:
        front = Packing(engine)
        front.run("get I 1")
        front.run("put I 1 5")
    finally:
        engine.stop()
    assert "ConnectFailed" in front.kinds, front.kinds


@pytest.mark.parametrize("name", ["Popen", "system", "RacConsoleApp", "Engine", "type", "object"])
def test_a_class_that_does_not_travel_is_refused(name: str) -> None:
    hostile = msgpack.packb([msgpack.ExtType(1, name.encode()), "rm -rf /"], use_bin_type=True)
    with pytest.raises(codec.DecodeError, match="no message of this release"):
        codec.unpack(hostile)


@pytest.mark.parametrize("data", [b"\xc1", b"\x92\x01", b"\xd4\x63\x00", b"\xc7\x02\x01\x92\x01"])
def test_bytes_that_are_no_message_are_refused(data: bytes) -> None:
    with pytest.raises(codec.DecodeError):
        codec.unpack(data)


def test_an_object_that_does_not_travel_is_not_packed() -> None:
    with pytest.raises(TypeError, match="does not travel"):
        codec.pack([object()])


@pytest.mark.parametrize(
    "hostile",
    [
        msgpack.ExtType(6, b"not a number"),  # a Decimal
        [msgpack.ExtType(2, b"VT")],  # an enum with no value
        [msgpack.ExtType(2, b"VT"), 999],  # an enum value it has not
        msgpack.ExtType(11, b"Q:1"),  # a variable of no type
    ],
    ids=["decimal", "enum-empty", "enum-value", "variable"],
)
def test_values_that_are_none_of_their_kind_close_the_channel(hostile: object) -> None:
    """Read as a connection reads them: the channel closes, no other error escapes."""
    from rac_console.agent.wire import Channel, ChannelClosed

    ours, theirs = socket.socketpair()
    with ours, theirs:
        theirs.sendall(msgpack.packb({"op": "batch", "events": [hostile]}, use_bin_type=True))
        with pytest.raises(ChannelClosed):
            Channel(ours).receive()


def test_a_listed_class_with_fields_that_fit_it_not_is_refused() -> None:
    wrong = msgpack.packb([msgpack.ExtType(1, b"VarRef"), 1, 2, 3, 4], use_bin_type=True)
    with pytest.raises(codec.DecodeError, match="cannot be made"):
        codec.unpack(wrong)
