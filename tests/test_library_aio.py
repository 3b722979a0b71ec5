"""``rac_console.aio``: the library awaited. Judged at a fake controller that answers each
GET with a value naming the request: gathered gets each get their own value, one request
in flight, in the order of the calls; a call cancelled before its turn is never sent."""

from __future__ import annotations

import asyncio
import threading
import time

import pytest

import rac_console as rac
from tests.support.servers import Memory, unused_port

HOST = "127.0.0.1"


async def test_gathered_gets_each_get_their_own_value_in_the_order_of_the_calls(
    recording,
) -> None:
    server = recording(Memory())
    async with rac.aio.connect(HOST, port=server.port) as rc:
        values = await asyncio.gather(*(rc.get("I", n) for n in range(40)))
        written, after = await asyncio.gather(rc.put("I", 3, 99), rc.get("I", 3))
    assert values == list(range(40))
    assert written == rac.Written("I3", 99, 3, 99, True) and after == 99
    gets = [f"GET:RC8:{n}:I:".encode() for n in range(40)]
    assert server.lines[:40] == gets  # one at a time, as called
    put_and_get = [b"GET:RC8:3:I:", b"PUT:RC8:3:I:3,99", b"GET:RC8:3:I:", b"GET:RC8:3:I:"]
    assert server.lines[40:] == put_and_get
    assert server.accepted == 1


async def test_a_put_cancelled_before_its_turn_is_never_sent(recording) -> None:
    release = threading.Event()
    server = recording(Memory(hold=(b"GET:RC8:1:I:", release)))
    async with rac.aio.connect(HOST, port=server.port, timeout=30) as rc:
        first = asyncio.ensure_future(rc.get("I", 1))  # held at the controller
        deadline = time.monotonic() + 10
        while b"GET:RC8:1:I:" not in server.lines:  # the get is on the wire, held
            assert time.monotonic() < deadline, "the first get never reached the controller"
            await asyncio.sleep(0.01)
        put = asyncio.ensure_future(rc.put("I", 2, 5))
        await asyncio.sleep(0)  # a yield, not a wait: the put is asked, behind the get
        put.cancel()
        await asyncio.wait([put])  # cancelled, while the get still waits for its answer
        release.set()
        assert await first == 1 and put.cancelled()
        assert await rc.get("I", 2) == 2
    assert server.lines == [b"GET:RC8:1:I:", b"GET:RC8:2:I:"]


async def test_what_the_sync_library_refuses_the_async_one_refuses(recording) -> None:
    server = recording(Memory())
    async with rac.aio.connect(HOST, port=server.port, read_only=True) as rc:
        with pytest.raises(rac.Refused, match="read-only"):
            await rc.put("I", 1, 5)
        with pytest.raises(rac.Refused, match="watch needs a variable"):
            rc.watch()
        assert rc.connection.writes == "read-only"
    with pytest.raises(rac.Refused, match="closed"):
        await rc.get("I", 1)
    assert server.lines == []


async def test_an_async_watch_reads_each_cycle_between_other_calls(recording) -> None:
    server = recording(Memory())
    rc = await rac.aio.connect(HOST, port=server.port)
    try:
        names: list[str] = []
        async for reading in rc.watch("I 4-5", every=0.01):
            names.append(reading.name)
            if len(names) == 4:
                break
        assert await rc.get("I", 9) == 9
    finally:
        await rc.close()
    assert names == ["I4", "I5", "I4", "I5"]


async def test_a_controller_that_cannot_be_reached_fails_the_await() -> None:
    with pytest.raises(rac.ConnectionFailed, match="cannot connect"):
        async with rac.aio.connect(HOST, port=unused_port()):
            pass


async def test_an_async_cell_routes_lines_as_the_console_does(recording, tmp_path) -> None:
    first, second = recording(Memory()), recording(Memory())
    config = tmp_path / "cell.toml"
    config.write_text(
        f'[target.r1]\nhost = "{HOST}"\nport = {first.port}\n'
        f'[target.r2]\nhost = "{HOST}"\nport = {second.port}\n',
        encoding="utf-8",
    )
    async with rac.aio.cell(["r1", "r2"], config=config) as cell:
        assert cell.names == ("r1", "r2")
        assert await cell.run("@r2 get I 7") == 7
    assert (first.lines, second.lines) == ([], [b"GET:RC8:7:I:"])
