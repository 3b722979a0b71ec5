"""The simulator's fast lane (Linux epoll): the same bytes as asyncio's transports, and
a session that leaves it for a transport keeps its order and is closed by stop()."""

from __future__ import annotations

import asyncio
import errno
import os
import socket
from typing import Any

import pytest

from rac_console.sim.controller import SimulatedController
from rac_console.sim.server import SimulatorServer

DEADLINE = 10.0  # a wait this long means hung: never a figure a test checks

needs_epoll = pytest.mark.skipif(not hasattr(__import__("select"), "epoll"), reason="Linux")

#: Reads sent one at a time, each after the replies to the one before: whole kept GETs,
#: pipelined lines, a line in two reads, CRLF, empty lines, PUTs, SIM: lines, junk.
READS = [
    b"GET:RC8:10:I:\r",
    b"GET:RC8:10:I:\r",
    b"GET:RC8:1:S:\rGET:RC8:1:P:\rGET:RC8:10:I:\r",
    b"GET:RC8:1",
    b"0:I:\r",
    b"GET:RC8:10:I:\r",
    b"GET:RC8:2:I:\r\nGET:RC8:3:I:\r\n",
    b"GET:RC8:10:I:\r",
    b"\r\r",
    b"PUT:RC8:10:I:3,42\rGET:RC8:10:I:\r",
    b"GET:RC8:10:I:\r",
    b"SIM:GET:\r",
    b"GET:RC8:10:I:\r",
    b"\xff\xfe\r",
    b"get:rc8:10:i:\r",
    b"GET:RC8:4" + b"4" * 300,  # no CR within 256 bytes: refused, then closed
]


async def until(holds: Any, what: str) -> None:
    """Wait on the event loop until ``holds()``, DEADLINE at most; asked again after each
    turn of the loop, so a state that lasts one turn (a session between the lane and its
    transport) is seen."""
    deadline = asyncio.get_running_loop().time() + DEADLINE
    while not holds():
        assert asyncio.get_running_loop().time() < deadline, f"timed out waiting for {what}"
        await asyncio.sleep(0)


async def exchange(sim: SimulatorServer) -> tuple[list[bytes], bytes]:
    """The replies to READS, and what follows them (b"": the server closed)."""
    reader, writer = await asyncio.open_connection(sim.host, sim.port)
    replies: list[bytes] = []
    for data in READS:
        writer.write(data)
        await writer.drain()
        expected = data.count(b"\r") or (1 if len(data) > 256 else 0)
        if not expected:  # half a line: read by the server as a read of its own
            await until(lambda: any(s.partial for s in sim.sessions), "the half line read")
        for _ in range(expected):
            replies.append(await asyncio.wait_for(reader.readuntil(b"\r"), DEADLINE))
    after = await asyncio.wait_for(reader.read(100), DEADLINE)
    writer.close()
    return replies, after


@needs_epoll
def test_the_lane_and_a_transport_answer_alike() -> None:
    async def served(fast_lane: bool) -> tuple[list[bytes], bytes, int]:
        controller = SimulatedController(clock=lambda: 0.0)
        async with SimulatorServer(controller=controller, fast_lane=fast_lane) as sim:
            replies, after = await exchange(sim)
        return replies, after, controller.requests

    lane, transport = asyncio.run(served(True)), asyncio.run(served(False))
    assert lane == transport
    replies, after, _ = lane
    assert replies[:2] == [b"0,3,0\r", b"0,3,0\r"]
    assert b"0,3,42\r" in replies
    assert after == b""


@needs_epoll
def test_a_client_that_does_not_read_gets_every_reply_in_order() -> None:
    """Far more replies than the sockets' buffers hold: the lane hands the session to a
    transport owing the rest, and everything arrives, in order, once the client reads."""
    lines = [f"GET:RC8:{n % 100}:{'IPSP'[n % 4]}:".encode() for n in range(20_000)]
    reference = SimulatedController(clock=lambda: 0.0)
    expected = b"".join(reference.handle(line)[0] for line in lines)

    async def scenario() -> tuple[bytes, list[bool]]:
        controller = SimulatedController(clock=lambda: 0.0)
        async with SimulatorServer(controller=controller) as sim:
            sock = socket.socket()
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            sock.connect((sim.host, sim.port))
            reader, writer = await asyncio.open_connection(sock=sock)
            writer.write(b"".join(line + b"\r" for line in lines))
            # Unread meanwhile: the lane hands the session over once its socket is full.
            await until(lambda: any(s.lane is None for s in sim.sessions), "the handover")
            replies = b""
            while len(replies) < len(expected):
                replies += await asyncio.wait_for(reader.read(1 << 16), DEADLINE)
            in_lane = [s.lane is not None for s in sim.sessions]
            writer.close()
            return replies, in_lane

    replies, in_lane = asyncio.run(scenario())
    assert replies == expected
    assert in_lane == [False]


@needs_epoll
def test_stop_closes_a_session_on_its_way_from_the_lane_to_a_transport() -> None:
    async def scenario() -> tuple[int, bytes]:
        sim = await SimulatorServer().start()
        client = socket.create_connection((sim.host, sim.port), timeout=DEADLINE)
        try:
            client.sendall(b"SIM:SET:delay_ms=1\r")  # faults on: the next read leaves the lane
            await asyncio.to_thread(client.recv, 100)
            client.sendall(b"GET:RC8:1:S:\r")
            await until(  # it has left the lane, and has no transport yet
                lambda: any(s.lane is None and s.sock is not None for s in sim.sessions),
                "the session between the lane and its transport",
            )
            await sim.stop()
            left = len(sim.sessions)
            return left, await asyncio.to_thread(client.recv, 100)
        finally:
            client.close()

    left, after = asyncio.run(scenario())
    assert left == 0
    assert after == b""


class _RegisterFailsOnce:
    """An epoll set whose first register() fails as the kernel's would out of memory."""

    def __init__(self, epoll: Any) -> None:
        self._epoll, self.failed = epoll, False

    def register(self, fd: int, mask: int) -> None:
        if not self.failed:
            self.failed = True
            raise OSError(errno.ENOMEM, os.strerror(errno.ENOMEM))
        self._epoll.register(fd, mask)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._epoll, name)


@needs_epoll
def test_a_client_the_lane_cannot_watch_is_closed_and_the_next_one_served() -> None:
    async def scenario() -> tuple[bytes, bytes, list[str]]:
        said: list[str] = []
        async with SimulatorServer(notify=said.append) as sim:
            lane = sim._lane
            assert lane is not None
            lane._epoll = _RegisterFailsOnce(lane._epoll)  # type: ignore[assignment]
            first_reader, first = await asyncio.open_connection(sim.host, sim.port)
            refused = await asyncio.wait_for(first_reader.read(100), DEADLINE)
            reader, writer = await asyncio.open_connection(sim.host, sim.port)
            writer.write(b"GET:RC8:1:S:\r")
            reply = await asyncio.wait_for(reader.readuntil(b"\r"), DEADLINE)
            first.close()
            writer.close()
            return refused, reply, said

    refused, reply, said = asyncio.run(scenario())
    assert refused == b""
    assert reply == b"0,8,RC8 simulator\r"
    assert len(said) == 1 and "cannot take a client" in said[0], said
