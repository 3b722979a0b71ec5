"""The session against the simulator and against misbehaving servers (each test's
handler on a :class:`~tests.support.servers.FaultServer`).

Every server binds 127.0.0.1 port 0 and runs on the test's own event loop (each test
is a plain function running it with ``asyncio.run``); the blocking session runs on a
worker thread of its own (:class:`AsyncSession`). Waits are conditions with deadlines.
"""

from __future__ import annotations

import asyncio
import select
import socket
from collections.abc import Awaitable, Callable
from typing import cast

import pytest

from rac_console.protocol import KINDS, Variant, kind_of
from rac_console.protocol.vartypes import VT
from rac_console.session import BadReply, Disconnected, Frame, RequestTimeout
from rac_console.sim.server import SimulatorServer
from tests.support.samples import SAMPLES
from tests.support.servers import Conn, FaultServer, Handler
from tests.support.sessions import AsyncSession

HOST = "127.0.0.1"
#: How long a test waits for what must come: a hung request fails the test, and nothing
#: checks how fast anything came (that is for benchmarks/).
DEADLINE = 10.0


# ----------------------------------------------------------------- helpers


def index_of(line: bytes) -> int:
    """The index field of a request line: ``GET:RC8:7:I:`` -> 7."""
    return int(line.split(b":")[2])


def echo_reply(line: bytes) -> bytes:
    """A GET I reply naming the request it answers: ``GET:RC8:7:I:`` -> ``0,3,7``."""
    return b"0,3,%d\r" % index_of(line)


async def until(condition: Callable[[], bool], timeout: float = DEADLINE) -> None:
    """Wait until ``condition()`` holds; fail the test past the deadline."""

    async def poll() -> None:
        while not condition():
            await asyncio.sleep(0.005)

    await asyncio.wait_for(poll(), timeout)


def frames_of(session: AsyncSession) -> list[Frame]:
    frames: list[Frame] = []
    session.add_frame_observer(frames.append)
    return frames


def last_sent(frames: list[Frame]) -> bytes:
    """The request line (no CR) of the last tx frame: what the last call put on the wire."""
    tx = [f.data for f in frames if f.direction == "tx"]
    assert tx, "nothing was sent"
    assert tx[-1].endswith(b"\r")
    return tx[-1][:-1]


async def unread(session: AsyncSession) -> bool:
    """True once bytes (or EOF) wait unread on the session's connection; asked from a
    thread of its own so that the servers on this loop keep running meanwhile."""
    return await asyncio.to_thread(session.has_unread, DEADLINE)


def run(coro: Awaitable[None]) -> None:
    asyncio.run(asyncio.wait_for(coro, 6 * DEADLINE))


# ------------------------------------------------- the simulator, normally


def test_get_put_send_raw_against_simulator() -> None:
    async def main() -> None:
        async with (
            SimulatorServer() as sim,
            AsyncSession(sim.host, sim.port, timeout=1.0) as session,
        ):
            frames = frames_of(session)
            put = await session.put(KINDS["I"], 10, Variant(VT.I4, 123))
            assert put.response.ok
            assert put.response.variant is None
            assert last_sent(frames) == b"PUT:RC8:10:I:3,123"
            assert put.raw == b"0"

            got = await session.get(KINDS["I"], 10)
            assert last_sent(frames) == b"GET:RC8:10:I:"
            assert got.text == "0,3,123"
            assert got.response.code == 0
            assert got.response.variant == Variant(VT.I4, 123)
            assert got.rtt >= 0
            assert session.last_rtt == got.rtt

            await session.put(KINDS["P"], 10, Variant(8196, [1.0, 2, 3, 4, 5, 6, -1]))
            pos = await session.get(KINDS["P"], 10)
            assert pos.response.variant is not None
            assert pos.response.variant.vt == 8196
            assert pos.response.variant.value == [1, 2, 3, 4, 5, 6, -1]

            raw = await session.send_raw("GET:RC8:10:I:")
            assert raw.text == "0,3,123"

            bad = await session.send_raw("PUT:RC8:10:11,0")
            assert not bad.response.ok
            assert bad.response.name == "E_INVALIDCOMMAND"
            assert session.state == "connected"

    run(main())


@pytest.mark.parametrize("sample", SAMPLES["get"], ids=lambda s: s["type"])
def test_vendor_get_sample_against_simulator(sample: dict) -> None:
    put_sample = next(
        p for p in SAMPLES["put"] if p["type"] == sample["type"] and p["index"] == sample["index"]
    )

    async def main() -> None:
        async with SimulatorServer() as sim, AsyncSession(sim.host, sim.port) as session:
            frames = frames_of(session)
            put = await session.send_raw(put_sample["request"])
            assert put.response.code == put_sample["result"] == 0
            assert put.response.variant is None

            reply = await session.send_raw(sample["request"])
            assert reply.response.code == sample["result"]
            variant = reply.response.variant
            assert variant is not None
            assert variant.vt == sample["vt"]
            assert variant.value == sample["value"]
            assert reply.text == sample["response"]

            typed = await session.get(KINDS[sample["type"]], sample["index"])
            assert last_sent(frames) == sample["request"].encode()
            assert typed.response.variant == variant

    run(main())


@pytest.mark.parametrize("sample", SAMPLES["put"], ids=lambda s: s["type"])
def test_vendor_put_sample_against_simulator(sample: dict) -> None:
    async def main() -> None:
        async with SimulatorServer() as sim, AsyncSession(sim.host, sim.port) as session:
            frames = frames_of(session)
            kind = KINDS[sample["type"]]
            before = (await session.get(kind, sample["index"])).response.variant
            assert before is not None
            assert before.value != sample["value"] or kind.code == "IO"

            reply = await session.send_raw(sample["request"])
            assert reply.text == sample["response"]
            assert reply.response.code == sample["result"]
            assert reply.response.variant is None

            after = (await session.get(kind, sample["index"])).response.variant
            assert after is not None
            assert after.vt == sample["vt"]
            assert after.value == sample["value"]

            # The typed put writes the same request as the vendor's sample.
            typed = await session.put(kind, sample["index"], Variant(sample["vt"], after.value))
            assert last_sent(frames) == sample["request"].encode()
            assert typed.response.ok

    run(main())


# ----------------------------------------------------------- late replies


def test_late_reply_times_out_and_is_never_taken_for_the_next_answer() -> None:
    """The first reply is held until the test lets it go, after the client gave up on
    it: the request can only end in its timeout, and the late reply, written once the
    next request was answered, is never taken for a later answer."""

    async def main() -> None:
        late = asyncio.Event()  # set by the test once the first request timed out

        async def handler(conn: Conn) -> None:
            while True:
                line = await conn.line()
                if len(conn.server.lines) == 1:
                    await late.wait()  # well past the client's timeout, whatever the load
                await conn.send(echo_reply(line))

        async with FaultServer(handler) as server:
            session = server.session(timeout=0.15)
            frames = frames_of(session)
            with pytest.raises(RequestTimeout):
                await session.get(KINDS["I"], 1)
            assert session.state == "closed"

            second = await session.get(KINDS["I"], 2)
            assert second.response.variant == Variant(VT.I4, 2)
            assert server.connections == 2

            # Once the late reply was written, nothing stale shows up.
            late.set()
            await until(lambda: 1 in server.ended)
            third = await session.get(KINDS["I"], 3)
            assert third.response.variant == Variant(VT.I4, 3)
            assert server.connections == 2
            rx = [f.data for f in frames if f.direction == "rx"]
            assert b"0,3,1\r" not in rx
            await session.close()

    run(main())


def test_no_reply_times_out_then_session_works_again() -> None:
    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            if conn.number == 1:
                continue  # the first connection never answers
            await conn.send(echo_reply(line))

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=0.2)
            with pytest.raises(RequestTimeout):  # the session's own timeout, not the deadline's
                await asyncio.wait_for(session.get(KINDS["I"], 1), DEADLINE)

            reply = await asyncio.wait_for(session.get(KINDS["I"], 2), DEADLINE)
            assert reply.response.variant == Variant(VT.I4, 2)
            assert server.connections == 2
            await session.close()

    run(main())


def test_timed_out_put_on_a_silent_server() -> None:
    async def handler(conn: Conn) -> None:
        while True:
            await conn.line()

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=0.1)
            with pytest.raises(RequestTimeout):
                await asyncio.wait_for(session.put(KINDS["I"], 1, Variant(VT.I4, 5)), DEADLINE)
            with pytest.raises(RequestTimeout):
                await asyncio.wait_for(session.send_raw("GET:RC8:1:I:"), DEADLINE)
            assert server.lines == [b"PUT:RC8:1:I:3,5", b"GET:RC8:1:I:"]
            await session.close()

    run(main())


# ----------------------------------------------------- closed mid-reply


def test_close_mid_reply_raises_disconnected_and_publishes_the_fragment() -> None:
    async def handler(conn: Conn) -> None:
        line = await conn.line()
        if conn.number == 1:
            await conn.send(b"0,3,1")
            return  # closes the connection with the reply cut short
        await conn.send(echo_reply(line))
        await conn.reader.read()

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            frames = frames_of(session)
            with pytest.raises(Disconnected) as caught:
                await session.get(KINDS["I"], 1)
            assert caught.value.raw == b"0,3,1"
            rx = [f for f in frames if f.direction == "rx"]
            assert [f.data for f in rx] == [b"0,3,1"]
            assert session.state == "closed"

            reply = await session.get(KINDS["I"], 2)
            assert reply.response.variant == Variant(VT.I4, 2)
            assert server.connections == 2
            await session.close()

    run(main())


def test_close_before_any_reply_raises_disconnected() -> None:
    async def handler(conn: Conn) -> None:
        await conn.line()

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            with pytest.raises(Disconnected) as caught:
                await session.get(KINDS["I"], 1)
            assert not caught.value.raw
            await session.close()

    run(main())


# ------------------------------------------- bytes on a fresh connection


def test_a_byte_waiting_on_a_fresh_connection_keeps_the_request_timeout(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A peer sends the LF of a CRLF as soon as the connection is made, then never
    answers: the request must still time out after ``timeout``."""

    async def handler(conn: Conn) -> None:
        await conn.send(b"\n")
        while True:
            await conn.line()  # never answered

    real_connect = socket.create_connection

    def connect_once_the_peer_spoke(*args: object, **kwargs: object) -> socket.socket:
        sock = real_connect(*args, **kwargs)  # type: ignore[arg-type]
        select.select([sock], [], [], DEADLINE)  # the LF has landed before the session looks
        return sock

    monkeypatch.setattr(socket, "create_connection", connect_once_the_peer_spoke)

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=0.2)
            try:
                with pytest.raises(RequestTimeout):  # its own timeout, not the deadline's
                    await asyncio.wait_for(session.get(KINDS["I"], 1), DEADLINE)
                assert server.lines == [b"GET:RC8:1:I:"]
            finally:
                session.session.interrupt()  # wake a request left waiting forever
                await session.close()

    run(main())


# --------------------------------------------------------- endless lines


def _endless_handler(state: dict) -> Handler:
    cap = 16 * 1024 * 1024

    async def handler(conn: Conn) -> None:
        await conn.line()
        chunk = b"A" * 4096
        try:
            while not conn.writer.is_closing() and state["sent"] < cap:
                state["sent"] += len(chunk)
                await conn.send(chunk)
        except ConnectionError:
            pass
        state["dropped"] = state["sent"] < cap

    return handler


@pytest.mark.parametrize("max_line", [1024, None], ids=["1KiB", "default-64KiB"])
def test_endless_line_is_a_bad_reply_within_the_bound(max_line: int | None) -> None:
    state = {"sent": 0, "dropped": False}

    async def main() -> None:
        async with FaultServer(_endless_handler(state)) as server:
            kwargs: dict[str, object] = {"timeout": 2.0}
            if max_line is not None:
                kwargs["max_line"] = max_line
            session = server.session(**kwargs)
            bound = max_line or 64 * 1024
            frames = frames_of(session)
            with pytest.raises(BadReply) as caught:  # not a RequestTimeout: the bound, not 2 s
                await asyncio.wait_for(session.get(KINDS["I"], 1), DEADLINE)
            assert f"no CR within {bound} bytes" in str(caught.value)  # the bound it was given
            assert caught.value.raw is None or len(caught.value.raw) <= bound
            assert sum(len(f.data) for f in frames if f.direction == "rx") <= bound
            assert session.state == "closed"
            # The client dropped the connection instead of reading on forever.
            await until(lambda: 1 in server.ended)
            assert state["dropped"]
            await session.close()

    run(main())


# -------------------------------------------------------------- garbage


def test_garbage_reply_is_a_bad_reply_with_raw_bytes() -> None:
    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            await conn.send(b"\xff\xfe garbage\r" if conn.number == 1 else echo_reply(line))

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            frames = frames_of(session)
            with pytest.raises(BadReply) as caught:
                await session.get(KINDS["I"], 1)
            assert caught.value.raw == b"\xff\xfe garbage"
            assert "\\xff\\xfe garbage" in str(caught.value)
            rx = [f for f in frames if f.direction == "rx"]
            assert [f.data for f in rx] == [b"\xff\xfe garbage\r"]
            assert rx[0].response is None and rx[0].problem  # refused once, and why

            reply = await session.get(KINDS["I"], 2)
            assert reply.response.variant == Variant(VT.I4, 2)
            assert server.connections == 2
            await session.close()

    run(main())


@pytest.mark.parametrize(
    "reply",
    [b"banana\r", b"0,99,1\r", b"0,3,abc\r", b"0x1234567890\r", b"\r", b"0,8204,(8,a\r"],
    ids=["word", "unknown-vt", "bad-int", "code-over-32-bits", "empty", "unbalanced"],
)
def test_unparsable_replies_are_bad_replies(reply: bytes) -> None:
    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            await conn.send(reply if conn.number == 1 else echo_reply(line))

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            with pytest.raises(BadReply) as caught:
                await session.send_raw("GET:RC8:1:I:")
            assert caught.value.raw == reply[:-1]
            again = await session.get(KINDS["I"], 2)
            assert again.response.variant == Variant(VT.I4, 2)
            await session.close()

    run(main())


# ------------------------------------------------------ split replies


def test_replies_split_byte_by_byte_are_parsed() -> None:
    replies = {
        b"GET:RC8:10:P:": b"0,8196,1,2,3,4,5,6,-1\r",
        b"GET:RC8:10:S:": b"0,8,Sample,Test\r",
        b"PUT:RC8:10:I:3,7": b"0\r",
        b"GET:RC8:10:I:": b"-2147024809\r",
    }

    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            for byte in replies[line]:
                await conn.send(bytes([byte]))
                await asyncio.sleep(0.002)

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.5)
            frames = frames_of(session)
            pos = await session.get(KINDS["P"], 10)
            assert pos.response.variant == Variant(8196, [1, 2, 3, 4, 5, 6, -1])
            text = await session.get(KINDS["S"], 10)
            assert text.response.variant == Variant(VT.BSTR, "Sample,Test")
            put = await session.put(KINDS["I"], 10, Variant(VT.I4, 7))
            assert put.response.ok
            err = await session.get(KINDS["I"], 10)
            assert err.response.code == 0x80070057
            assert err.response.name == "E_INVALIDARG"
            assert server.connections == 1
            rx = [f.data for f in frames if f.direction == "rx"]
            assert rx == list(replies.values())
            await session.close()

    run(main())


def test_crlf_replies_are_accepted_on_one_connection() -> None:
    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            await conn.send(echo_reply(line)[:-1] + b"\r")
            await conn.send(b"\n")

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            for index in range(1, 6):
                reply = await session.get(KINDS["I"], index)
                assert reply.response.variant == Variant(VT.I4, index)
            assert server.connections == 1
            await session.close()

    run(main())


# ------------------------------------------------------ unsolicited bytes


@pytest.mark.parametrize(
    "extra",
    [b"0,3,999\r", b"0,3,9", b"\xff"],
    ids=["line", "fragment", "byte"],
)
def test_extra_line_after_a_reply_is_never_the_next_answer(extra: bytes) -> None:
    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            await conn.send(echo_reply(line) + (extra if conn.number == 1 else b""))

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            frames = frames_of(session)
            # The extra bytes come in the reply's own read: neither line is taken.
            with pytest.raises(BadReply, match="more than one line"):
                await session.get(KINDS["I"], 1)
            await until(lambda: any(f.unsolicited for f in frames))
            assert session.state == "closed"

            second = await session.get(KINDS["I"], 2)
            assert second.response.variant == Variant(VT.I4, 2)
            assert server.connections == 2
            unsolicited = [f.data for f in frames if f.unsolicited]
            assert b"".join(unsolicited).startswith(extra.rstrip(b"\r"))
            await session.close()

    run(main())


def test_spontaneous_line_between_requests_drops_the_connection() -> None:
    stray_sent: list[bool] = []

    async def handler(conn: Conn) -> None:
        line = await conn.line()
        await conn.send(echo_reply(line))
        if conn.number == 1:
            await asyncio.sleep(0.05)
            await conn.send(b"0,3,777\r")  # nobody asked
            stray_sent.append(True)
        while True:
            line = await conn.line()
            await conn.send(echo_reply(line))

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            frames = frames_of(session)
            first = await session.get(KINDS["I"], 1)
            assert first.response.variant == Variant(VT.I4, 1)
            await until(lambda: bool(stray_sent))
            # The session reads only for a request: the stray waits for the next one.
            assert await unread(session)
            assert session.state == "connected"

            for index in (2, 3):
                reply = await session.get(KINDS["I"], index)
                assert reply.response.variant == Variant(VT.I4, index)
            assert [f.data for f in frames if f.unsolicited] == [b"0,3,777\r"]
            # Logged before the request it would have answered went out, never as its reply.
            assert [(f.direction, f.unsolicited) for f in frames[2:5]] == [
                ("rx", True),
                ("tx", False),
                ("rx", False),
            ]
            assert server.connections == 2
            await session.close()

    run(main())


def test_two_replies_to_one_request_do_not_shift_later_answers() -> None:
    duplicate_sent: list[bool] = []

    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            await conn.send(echo_reply(line))
            if index_of(line) == 1:
                await asyncio.sleep(0.02)
                await conn.send(echo_reply(line))  # the same answer again, a little later
                duplicate_sent.append(True)

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            frames = frames_of(session)
            await session.get(KINDS["I"], 1)
            await until(lambda: bool(duplicate_sent))
            assert await unread(session)  # the duplicate waits when the next get is made
            for index in range(2, 6):
                reply = await session.get(KINDS["I"], index)
                assert reply.response.variant == Variant(VT.I4, index)
            assert [f.data for f in frames if f.unsolicited] == [b"0,3,1\r"]
            assert server.connections == 2
            await session.close()

    run(main())


# ------------------------------------------------ replies that cannot belong


@pytest.mark.parametrize(
    ("request_kind", "reply"),
    [
        ("get P", b"0,3,5\r"),
        ("put", b"0,3,5\r"),
        ("get I", b"0,8,text\r"),
        ("get P", b"0,8196,1,2,3\r"),
        ("get V", b"0,8196,1,2,3,4\r"),
        ("get S", b"0,3,5\r"),
        ("get I", b"0\r"),
    ],
    ids=["P-got-I", "PUT-got-value", "I-got-S", "P-got-3", "V-got-4", "S-got-I", "I-got-none"],
)
def test_reply_that_cannot_belong_is_a_bad_reply(request_kind: str, reply: bytes) -> None:
    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            await conn.send(reply if conn.number == 1 else echo_reply(line))

    async def main() -> None:
        async with FaultServer(handler) as server:
            session = server.session(timeout=1.0)
            frames = frames_of(session)
            with pytest.raises(BadReply) as caught:
                if request_kind == "put":
                    await session.put(KINDS["I"], 10, Variant(VT.I4, 1))
                else:
                    await session.get(KINDS[request_kind.split()[1]], 10)
            assert caught.value.raw == reply[:-1]
            rx = [f for f in frames if f.direction == "rx"]
            assert [f.data for f in rx] == [reply]
            assert rx[0].response is not None and rx[0].problem  # parsed, and refused
            assert session.state == "closed"
            again = await session.get(KINDS["I"], 4)
            assert again.response.variant == Variant(VT.I4, 4)
            assert server.connections == 2
            await session.close()

    run(main())


def test_error_reply_to_a_get_is_not_a_bad_reply() -> None:
    async def handler(conn: Conn) -> None:
        while True:
            await conn.line()
            await conn.send(b"0x80070057\r")

    async def main() -> None:
        async with FaultServer(handler) as server, server.session(timeout=1.0) as session:
            reply = await session.get(KINDS["P"], 10)
            assert not reply.response.ok
            assert reply.response.name == "E_INVALIDARG"
            assert server.connections == 1

    run(main())


# ------------------------------------------------------------ concurrency


def test_concurrent_gets_against_the_simulator() -> None:
    """Calls made at once serialize on the session's owner thread: one request in
    flight, and each reply matched to its own request."""

    async def main() -> None:
        async with SimulatorServer() as sim, AsyncSession(sim.host, sim.port) as session:
            for index in range(10, 60):
                await session.put(KINDS["I"], index, Variant(VT.I4, index * 7))
                await session.put(KINDS["S"], index, Variant(VT.BSTR, f"s{index}"))
            frames = frames_of(session)
            calls = [session.get(KINDS["I"], index) for index in range(10, 60)]
            calls += [session.get(KINDS["S"], index) for index in range(10, 60)]
            replies = await asyncio.gather(*calls)
            for index, reply in zip(range(10, 60), replies[:50], strict=True):
                assert reply.response.variant == Variant(VT.I4, index * 7)
            for index, reply in zip(range(10, 60), replies[50:], strict=True):
                assert reply.response.variant == Variant(VT.BSTR, f"s{index}")
            # Each request went out once, and its reply came before the next request.
            assert [f.direction for f in frames] == ["tx", "rx"] * 100
            sent = sorted(f.data for f in frames if f.direction == "tx")
            assert sent == sorted(
                [b"GET:RC8:%d:I:\r" % index for index in range(10, 60)]
                + [b"GET:RC8:%d:S:\r" % index for index in range(10, 60)]
            )
            for tx, rx in zip(frames[::2], frames[1::2], strict=True):
                index = index_of(tx.data)
                assert rx.response is not None
                if tx.data.endswith(b":I:\r"):
                    assert rx.response.variant == Variant(VT.I4, index * 7)
                else:
                    assert rx.response.variant == Variant(VT.BSTR, f"s{index}")
            assert len(sim.sessions) == 1

    run(main())


class _StrictProtocol(asyncio.Protocol):
    """Answers after a short delay and notes any request that arrives before its answer."""

    def __init__(self, record: dict) -> None:
        self.record = record
        self.buffer = b""
        self.busy = False
        self.transport: asyncio.Transport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]
        self.record["connections"] += 1

    def data_received(self, data: bytes) -> None:
        self.buffer += data
        while b"\r" in self.buffer:
            line, _, self.buffer = self.buffer.partition(b"\r")
            if self.busy:
                self.record["overlaps"].append(line)
            self.busy = True
            self.record["lines"].append(line)
            asyncio.get_running_loop().call_later(0.003, self.answer, line)

    def answer(self, line: bytes) -> None:
        self.busy = False
        if self.transport is not None and not self.transport.is_closing():
            self.transport.write(echo_reply(line))


def test_concurrent_gets_never_overlap_on_one_connection() -> None:
    record: dict = {"connections": 0, "overlaps": [], "lines": []}

    async def main() -> None:
        loop = asyncio.get_running_loop()
        server = await loop.create_server(lambda: _StrictProtocol(record), HOST, 0)
        port = server.sockets[0].getsockname()[1]
        try:
            async with AsyncSession(HOST, port, timeout=1.5) as session:
                replies = await asyncio.gather(
                    *(session.get(KINDS["I"], index) for index in range(40))
                )
                for index, reply in enumerate(replies):
                    assert reply.response.variant == Variant(VT.I4, index)
                assert record["overlaps"] == []
                assert len(record["lines"]) == 40
                assert record["connections"] == 1
        finally:
            server.close()
            await server.wait_closed()

    run(main())


# -------------------------------------------------------- frame observers


def test_each_exchange_publishes_a_tx_and_an_rx_frame() -> None:
    async def main() -> None:
        async with SimulatorServer() as sim, AsyncSession(sim.host, sim.port) as session:
            frames = frames_of(session)
            await session.put(KINDS["I"], 10, Variant(VT.I4, 5))
            await session.get(KINDS["I"], 10)
            await session.send_raw("GET:RC8:10:S:")
            assert [f.direction for f in frames] == ["tx", "rx"] * 3
            assert [f.data for f in frames] == [
                b"PUT:RC8:10:I:3,5\r",
                b"0\r",
                b"GET:RC8:10:I:\r",
                b"0,3,5\r",
                b"GET:RC8:10:S:\r",
                b"0,8,\r",
            ]
            for frame in frames:
                assert frame.data.endswith(b"\r")
                assert not frame.unsolicited
                assert frame.time > 0
                if frame.direction == "tx":
                    assert frame.rtt is None
                    assert frame.response is None and frame.problem is None
                else:
                    assert frame.rtt is not None
                    assert 0 <= frame.rtt < DEADLINE  # a round trip, not a clock reading
                    # The reply as the session parsed it, once, and no problem with it.
                    assert frame.response is not None and frame.problem is None
            assert [f.response.variant for f in frames[1::2]] == [  # type: ignore[union-attr]
                None,
                Variant(VT.I4, 5),
                Variant(VT.BSTR, ""),
            ]

            observer_calls: list[Frame] = []
            session.add_frame_observer(observer_calls.append)
            session.session.remove_frame_observer(observer_calls.append)
            await session.get(KINDS["I"], 10)
            assert observer_calls == []
            assert len(frames) == 8

    run(main())


def slow_echo(delay: float) -> Handler:
    """Answers each request with its index (``0,3,n``), ``delay`` seconds after it came."""

    async def handler(conn: Conn) -> None:
        while True:
            line = await conn.line()
            await asyncio.sleep(delay)
            await conn.send(echo_reply(line))

    return handler


def test_a_cancelled_request_never_leaves_its_reply_for_the_next() -> None:
    async def scenario() -> int:
        async with FaultServer(slow_echo(0.2)) as server, server.session(timeout=2) as session:
            with pytest.raises(TimeoutError):
                # The await is given up; the GET itself still runs on the session's
                # thread and takes its own reply, so the next request waits for it.
                await asyncio.wait_for(session.get(kind_of("I"), 1), 0.05)
            reply = await session.get(kind_of("I"), 2)
            value: int = cast(Variant, reply.response.variant).value
            return value

    assert asyncio.run(scenario()) == 2


def test_a_failing_frame_observer_does_not_break_the_session() -> None:
    from rac_console.sim.server import SimulatorServer

    async def scenario() -> list[int]:
        async with SimulatorServer() as sim, AsyncSession(sim.host, sim.port) as session:

            def broken(frame: Frame) -> None:
                raise OSError(28, "No space left on device")

            session.add_frame_observer(broken)
            await session.put(kind_of("I"), 1, Variant(3, 11))
            await session.put(kind_of("I"), 2, Variant(3, 22))
            first = await session.get(kind_of("I"), 1)
            second = await session.get(kind_of("I"), 2)
            return [cast(Variant, r.response.variant).value for r in (first, second)]

    assert asyncio.run(scenario()) == [11, 22]
