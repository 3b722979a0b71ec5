"""The session and the console against the simulator's injected faults, and the
simulator against hostile clients.

The simulator runs on the test's event loop; the blocking session on a worker thread of
its own (:class:`AsyncSession`)."""

from __future__ import annotations

import asyncio
import os
import socket
import time
from typing import cast

import pytest

from rac_console.engine import Engine
from rac_console.protocol import Variant, kind_of, parse_response
from rac_console.session import BadReply, Disconnected, RequestTimeout
from rac_console.sim.controller import SimulatedController
from rac_console.sim.faults import GARBAGE, FaultPlan, FaultSettings
from rac_console.sim.server import SimulatorServer
from tests.support.drivers import Front
from tests.support.sessions import AsyncSession

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

INT = kind_of("I")
COUNT = 60  # distinct variables I0..I59 hold 1000+index, so any value names its request


def expected(index: int) -> int:
    return 1000 + index


async def faulty_simulator(**settings: object) -> SimulatorServer:
    simulator = SimulatorServer(faults=FaultSettings(**settings), transcript=True)  # type: ignore[arg-type]
    controller = cast(SimulatedController, simulator.controller)  # not a replay
    store = controller._store["I"]
    for index in range(COUNT):
        store[index] = expected(index)
    controller.value = lambda kind, index: controller._store[kind.code][index]  # type: ignore[method-assign]
    return await simulator.start()


async def until(predicate, what: str, timeout: float = 5.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(0.02)


def test_fault_plan_is_reproducible_from_its_seed() -> None:
    settings = FaultSettings(jitter_ms=5, error_rate=0.3, drop_every=4, garble_every=3, seed=7)
    first = [FaultPlan(settings).next() for _ in range(1)]
    plan_a, plan_b = FaultPlan(settings), FaultPlan(settings)
    a = [plan_a.next() for _ in range(50)]
    b = [plan_b.next() for _ in range(50)]
    assert a == b and first[0] == a[0]
    assert [f.action for f in a[:4]] == [a[0].action, a[1].action, "garble", "drop"]
    assert any(f.action == "error" for f in a)
    assert a != [
        FaultPlan(FaultSettings(jitter_ms=5, error_rate=0.3, seed=8)).next() for _ in range(50)
    ]


FAULT_MODES: dict[str, dict[str, object]] = {
    "delay+jitter": {"delay_ms": 5, "jitter_ms": 5},
    "slow": {"slow_every": 15},
    "drop": {"drop_every": 7},
    "stall": {"stall_every": 9},
    "garble": {"garble_every": 5},
    "split": {"split": True},
    "extra": {"extra_every": 6},
    "errors": {"error_rate": 0.2},
    "everything": {
        "jitter_ms": 2,
        "drop_every": 11,
        "stall_every": 13,
        "garble_every": 7,
        "extra_every": 5,
        "error_rate": 0.1,
        "split": True,
    },
}


@pytest.mark.parametrize("mode", FAULT_MODES, ids=list(FAULT_MODES))
def test_the_client_never_takes_a_reply_for_another_request(mode: str) -> None:
    """Every answer the client accepts is the one the simulator sent for that request;
    every failure is a clear per-request error; the session always recovers."""

    async def scenario() -> tuple[list[int], list[str], int, int]:
        simulator = await faulty_simulator(seed=1, **FAULT_MODES[mode])
        wrong, failures = [], []
        try:
            # A fault that fails requests needs them to time out soon; where none may fail
            # (a reply late or in pieces), a busy machine must not make one time out.
            timeout = 10.0 if mode in ("delay+jitter", "split") else 0.4
            async with AsyncSession(simulator.host, simulator.port, timeout=timeout) as session:
                for _ in range(2):
                    for index in range(COUNT):
                        try:
                            reply = await session.get(INT, index)
                        except (RequestTimeout, Disconnected, BadReply) as exc:
                            failures.append(type(exc).__name__)
                            if isinstance(exc, BadReply):
                                assert exc.raw is not None
                            continue
                        if reply.response.ok:
                            if cast(Variant, reply.response.variant).value != expected(index):
                                wrong.append(index)
                        else:
                            failures.append(reply.response.name or hex(reply.response.code))
        finally:
            await simulator.stop()
        transcript = simulator.transcript or []
        return wrong, failures, len(transcript), len({entry[0] for entry in transcript})

    wrong, failures, requests, connections = asyncio.run(scenario())
    assert wrong == []
    assert len(failures) < 2 * COUNT  # the session kept working
    if mode == "extra":
        # An extra line in the reply's own write: two lines for one request, neither is
        # taken (a bad reply); the connection is reset and the next request is answered.
        assert set(failures) <= {"BadReply"} and connections > 1
    elif mode in ("delay+jitter", "split"):
        assert failures == [] and connections == 1
    elif mode == "drop":
        # A connection dropped before any byte of a GET's reply: the GET is sent once
        # more on a fresh connection (a read changes nothing), so nothing fails.
        assert connections > 1 and failures == [], (connections, failures)
    else:
        assert failures, "the fault was never exercised"
    assert requests >= 2 * COUNT


def test_a_garbled_reply_is_reported_with_its_bytes_escaped() -> None:
    async def scenario() -> tuple[str, bytes | None]:
        simulator = await faulty_simulator(garble_every=1)
        try:
            async with AsyncSession(simulator.host, simulator.port, timeout=0.5) as session:
                with pytest.raises(BadReply) as caught:
                    await session.get(INT, 1)
                return str(caught.value), caught.value.raw
        finally:
            await simulator.stop()

    message, raw = asyncio.run(scenario())
    assert raw == GARBAGE
    assert "\\xff\\xfe" in message and "\xff" not in message


def test_the_console_marks_failed_rows_stale_and_keeps_good_values_right() -> None:
    async def scenario() -> tuple[dict[str, tuple[str, bool, object]], list[str]]:
        simulator = await faulty_simulator(
            seed=3, drop_every=9, stall_every=11, garble_every=13, error_rate=0.05, split=True
        )
        engine = Engine(simulator.host, simulator.port, timeout=0.3, interval=0)
        front = Front(engine)  # reads the batches as every front end does

        def polls() -> int:
            return sum(1 for frame in front.frames if frame.poll and frame.direction == "tx")

        def answered() -> set[str]:
            return {result.line or "" for result in front.results.values()}

        await asyncio.to_thread(engine.start)
        try:
            engine.submit(f"watch I 0-{COUNT - 1}")

            def polled() -> bool:
                front.drain()
                return polls() > 3 * COUNT

            await until(polled, "three poll cycles", timeout=60)
            engine.submit("pause")

            def paused() -> bool:
                front.drain()
                return "pause" in answered()

            await until(paused, "the pause")
        finally:
            await asyncio.to_thread(engine.stop)
            await simulator.stop()
        front.drain()
        shown = {
            name: (view.status, view.stale, view.variant.value if view.variant else None)
            for name, view in front.rows.items()
        }
        alerts = front.alerts
        return shown, alerts

    rows, alerts = asyncio.run(scenario())
    assert alerts == []  # the engine never stopped on an internal error
    assert len(rows) == COUNT
    for name, (status, stale, value) in rows.items():
        index = int(name[1:])
        assert value in (None, expected(index)), name
        assert stale == (status != "OK" and value is not None)  # stale: a value kept


def test_max_sessions_refuses_the_extra_connection() -> None:
    async def scenario() -> tuple[bytes, bytes, int]:
        simulator = await faulty_simulator(max_sessions=2)
        try:
            first = await asyncio.open_connection(simulator.host, simulator.port)
            second = await asyncio.open_connection(simulator.host, simulator.port)
            await until(lambda: len(simulator.sessions) == 2, "two sessions")
            third = await asyncio.open_connection(simulator.host, simulator.port)
            refused = await asyncio.wait_for(third[0].read(), 2)
            first[1].write(b"GET:RC8:1:I:\r")
            answered = await asyncio.wait_for(first[0].readuntil(b"\r"), 2)
            for _, writer in (first, second, third):
                writer.close()
            return refused, answered, simulator.refused
        finally:
            await simulator.stop()

    refused, answered, count = asyncio.run(scenario())
    assert refused == b"" and answered == b"0,3,1001\r" and count == 1


def test_faults_can_be_changed_while_the_simulator_runs() -> None:
    async def scenario() -> list[bytes]:
        simulator = await faulty_simulator()
        try:
            reader, writer = await asyncio.open_connection(simulator.host, simulator.port)
            replies = []
            for line in (
                b"SIM:SET:garble_every=1",
                b"GET:RC8:1:I:",
                b"SIM:SET:garble_every=0",
                b"GET:RC8:1:I:",
                b"SIM:GET:",
                b"SIM:SET:bogus=1",
            ):
                writer.write(line + b"\r")
                replies.append(await asyncio.wait_for(reader.readuntil(b"\r"), 2))
            writer.close()
            return replies
        finally:
            await simulator.stop()

    replies = asyncio.run(scenario())
    assert replies[0] == b"0\r" and replies[1] == GARBAGE + b"\r"
    assert replies[2] == b"0\r" and replies[3] == b"0,3,1001\r"
    assert b"garble_every=0" in replies[4]
    assert parse_response(replies[5][:-1].decode()).name == "E_INVALIDARG"


# ------------------------------------------------------------- hostile clients


def open_sockets() -> int:
    return len(os.listdir("/proc/self/fd"))


async def still_answers(simulator: SimulatorServer) -> bytes:
    reader, writer = await asyncio.open_connection(simulator.host, simulator.port)
    writer.write(b"GET:RC8:1:S:\r")
    reply = await asyncio.wait_for(reader.readuntil(b"\r"), 2)
    writer.close()
    await writer.wait_closed()
    return reply


@pytest.mark.parametrize("faults", [{}, {"delay_ms": 1}], ids=["fast-path", "fault-path"])
def test_the_simulator_survives_a_storm_of_hostile_clients(faults: dict) -> None:
    async def scenario() -> tuple[bytes, int, int, int]:
        simulator = await faulty_simulator(**faults)
        await asyncio.sleep(0.05)
        baseline = open_sockets()
        try:
            for _ in range(10):  # 2,000 connections opened and dropped, some mid-line
                batch = await asyncio.gather(
                    *(asyncio.open_connection(simulator.host, simulator.port) for _ in range(200))
                )
                for n, (_, writer) in enumerate(batch):
                    if n % 3 == 0:
                        writer.write(b"GET:RC8:1")
                    writer.transport.abort()
            junk = socket.create_connection((simulator.host, simulator.port))
            junk.sendall(os.urandom(4000))  # binary junk, no CR within 256 bytes
            half = socket.create_connection((simulator.host, simulator.port))
            half.sendall(b"GET:RC8:1:S:\r")
            half.shutdown(socket.SHUT_WR)  # half-closed: it still gets its answer
            half.settimeout(2)
            half_reply = await asyncio.to_thread(half.recv, 100)
            deaf = socket.create_connection((simulator.host, simulator.port))
            deaf.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            deaf.setblocking(False)
            sent, refusals = 0, 0
            while refusals < 20:  # a client that sends and never reads, until it cannot send
                try:
                    sent += deaf.send(b"GET:RC8:1:P:\r" * 1000)
                    refusals = 0
                except BlockingIOError:
                    refusals += 1
                    await asyncio.sleep(0.01)
            await asyncio.sleep(0.2)
            buffered = max(
                (
                    s._transport.get_write_buffer_size()
                    for s in simulator.sessions
                    if s._transport is not None
                ),
                default=0,
            )
            reply = await still_answers(simulator)
            for sock in (junk, half, deaf):
                sock.close()
            await until(lambda: not simulator.sessions, "every session to end")
            await asyncio.sleep(0.05)
            return reply + half_reply, buffered, open_sockets() - baseline, sent
        finally:
            await simulator.stop()

    replies, buffered, leaked, sent = asyncio.run(scenario())
    assert replies == b"0,8,RC8 simulator\r0,8,RC8 simulator\r"
    assert buffered < 1_000_000, "a client that never reads made the server buffer without bound"
    assert sent > 0
    assert leaked <= 0
