"""The simulator over real loopback sockets: what a client sees for each request."""

from __future__ import annotations

import asyncio

import pytest

from rac_console.protocol import hresult, parse_response
from rac_console.protocol.hresult import E_INVALIDARG
from rac_console.sim.controller import SimulatedController
from rac_console.sim.server import SimulatorServer

DEADLINE = 10.0  # a wait this long means hung: never a figure a test checks


class Line:
    """A raw client: send bytes, read one CR-terminated reply."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader, self.writer = reader, writer

    async def ask(self, data: bytes) -> str:
        self.writer.write(data)
        reply = await asyncio.wait_for(self.reader.readuntil(b"\r"), DEADLINE)
        return reply[:-1].decode("ascii")

    async def closed_by_peer(self) -> bool:
        return await asyncio.wait_for(self.reader.read(1), DEADLINE) == b""


async def connect(sim: SimulatorServer) -> Line:
    return Line(*await asyncio.open_connection(sim.host, sim.port))


def run(coro_fn, controller: SimulatedController | None = None):
    async def main():
        async with SimulatorServer(controller=controller) as sim:
            return await coro_fn(sim)

    return asyncio.run(main())


def code(reply: str) -> int:
    return parse_response(reply).code


def test_get_answers_each_type_with_its_vartype_and_size() -> None:
    async def scenario(sim: SimulatorServer) -> dict[str, str]:
        line = await connect(sim)
        return {
            t: await line.ask(f"GET:RC8:10:{t}:\r".encode())
            for t in ("I", "F", "D", "S", "V", "P", "J", "T", "IO")
        }

    replies = run(scenario)
    expected = {
        "I": (3, None),
        "F": (4, None),
        "D": (5, None),
        "S": (8, None),
        "V": (8196, 3),
        "P": (8196, 7),
        "J": (8196, 8),
        "T": (8196, 10),
        "IO": (11, None),
    }
    for kind, (vt, count) in expected.items():
        response = parse_response(replies[kind])
        assert response.ok and response.variant is not None, replies[kind]
        assert response.variant.vt == vt
        if count:
            assert len(response.variant.value) == count


def test_put_stores_converts_and_checks_values() -> None:
    async def scenario(sim: SimulatorServer) -> list[str]:
        line = await connect(sim)
        asks = [
            b"PUT:RC8:10:I:2,100\r",
            b"GET:RC8:10:I:\r",
            b"PUT:RC8:11:F:4,123.456789\r",
            b"GET:RC8:11:F:\r",
            b"PUT:RC8:12:P:8194,1,2,3,4,5,6,-1\r",
            b"GET:RC8:12:P:\r",
            b"PUT:RC8:13:S:8,Sample,Test\r",
            b"GET:RC8:13:S:\r",
            b"PUT:RC8:14:IO:11,-1\r",
            b"GET:RC8:14:IO:\r",
            b"PUT:RC8:10:I:8,abc\r",
            b"PUT:RC8:10:P:8196,1,2,3\r",
            b"PUT:RC8:10:I:5,1e12\r",
            b"PUT:RC8:10:F:5,1e300\r",
            b"PUT:RC8:10:I:3,\r",
        ]
        return [await line.ask(a) for a in asks]

    r = run(scenario)
    assert r[0:2] == ["0", "0,3,100"]
    assert r[2:4] == ["0", "0,4,123.45679"]  # stored as float32
    assert r[4:6] == ["0", "0,8196,1,2,3,4,5,6,-1"]
    assert r[6:8] == ["0", "0,8,Sample,Test"]
    assert r[8:10] == ["0", "0,11,-1"]
    assert code(r[10]) == hresult.E_INVALIDARGTYPE
    assert [code(x) for x in r[11:]] == [hresult.E_INVALIDARG] * 4


@pytest.mark.parametrize(
    "request_line, expected",
    [
        (b"FOO:RC8:10:I:", hresult.E_INVALIDCOMMAND),
        (b"", hresult.E_INVALIDCOMMAND),
        (b"GET:RC8:10:I", hresult.E_INVALIDCOMMAND),
        (b"PUT:RC8:10:11,0", hresult.E_INVALIDCOMMAND),
        (b"GET:RC8:10:X:", hresult.E_INVALIDCOMMAND),
        (b"GET:RC8:ten:I:", hresult.E_INVALIDCOMMAND),
        (b"GET:RC9:10:I:", hresult.E_INVALIDCOMMAND),
        (b"GET:RC8:100:I:", hresult.E_INVALIDARG),
        (b"GET:RC8:512:IO:", hresult.E_INVALIDARG),
        (b"GET:RC8:1:I:\xff\xfe", hresult.E_INVALIDCOMMAND),
        (b"\x00\x01\x02", hresult.E_INVALIDCOMMAND),
        (b"PUT:RC8:0:IO:11,-1", hresult.E_ACCESSDENIED),
    ],
)
def test_bad_requests_get_an_error_and_the_session_goes_on(request_line: bytes, expected: int):
    async def scenario(sim: SimulatorServer) -> tuple[str, str]:
        line = await connect(sim)
        return await line.ask(request_line + b"\r"), await line.ask(b"GET:RC8:1:S:\r")

    error, after = run(scenario)
    assert code(error) == expected
    assert after == "0,8,RC8 simulator"


def test_leading_blanks_are_ignored() -> None:
    async def scenario(sim: SimulatorServer) -> str:
        return await (await connect(sim)).ask(b" \t GET:RC8:1:S:\r")

    assert run(scenario) == "0,8,RC8 simulator"


def test_a_request_over_256_bytes_is_answered_then_the_connection_closes() -> None:
    async def scenario(sim: SimulatorServer) -> tuple[str, bool, str, str]:
        line = await connect(sim)
        ok = await line.ask(b"PUT:RC8:1:S:8," + b"x" * (256 - 15) + b"\r")  # exactly 256
        long = await connect(sim)
        error = await long.ask(b"PUT:RC8:1:S:8," + b"x" * (256 - 14) + b"\r")  # 257
        closed = await long.closed_by_peer()
        endless = await connect(sim)
        endless.writer.write(b"y" * 300)  # no CR at all
        no_cr = await asyncio.wait_for(endless.reader.readuntil(b"\r"), DEADLINE)
        return ok, closed, error, no_cr.decode()

    ok, closed, error, no_cr = run(scenario)
    assert ok == "0"
    assert code(error) == hresult.E_INVALIDRCVPACKET and closed
    assert code(no_cr[:-1]) == hresult.E_INVALIDRCVPACKET


def test_a_client_leaving_mid_line_does_not_disturb_the_others() -> None:
    async def scenario(sim: SimulatorServer) -> tuple[str, int]:
        steady = await connect(sim)
        for _ in range(20):
            quitter = await connect(sim)
            quitter.writer.write(b"GET:RC8:1")
            await quitter.writer.drain()
            quitter.writer.transport.abort()
        reply = await steady.ask(b"GET:RC8:1:S:\r")
        deadline = asyncio.get_running_loop().time() + DEADLINE
        while len(sim.sessions) > 1 and asyncio.get_running_loop().time() < deadline:
            await asyncio.sleep(0.01)
        return reply, len(sim.sessions)

    reply, sessions = run(scenario)
    assert reply == "0,8,RC8 simulator"
    assert sessions == 1


def test_many_concurrent_sessions_are_served() -> None:
    async def scenario(sim: SimulatorServer) -> list[str]:
        lines = [await connect(sim) for _ in range(50)]

        async def client(n: int, line: Line) -> str:
            await line.ask(f"PUT:RC8:{n}:I:3,{n * 7}\r".encode())
            return await line.ask(f"GET:RC8:{n}:I:\r".encode())

        return await asyncio.gather(*(client(n + 10, ln) for n, ln in enumerate(lines[:50])))

    replies = run(scenario)
    assert replies == [f"0,3,{(n + 10) * 7}" for n in range(50)]


def test_some_variables_move_by_themselves() -> None:
    now = [0.0]
    controller = SimulatedController(clock=lambda: now[0])
    from rac_console.protocol import kind_of

    before = [controller.value(kind_of(k), 0) for k in ("I", "P", "J")]
    inputs_before = [controller.value(kind_of("IO"), n) for n in range(8)]
    now[0] = 3.7
    after = [controller.value(kind_of(k), 0) for k in ("I", "P", "J")]
    inputs_after = [controller.value(kind_of("IO"), n) for n in range(8)]
    assert all(a != b for a, b in zip(before, after, strict=True))
    assert inputs_before != inputs_after
    assert controller.value(kind_of("P"), 1) == [350.0, 0.0, 450.0, 180.0, 0.0, 180.0, 5.0]


# ------------------------------------------- kept replies (the fast path's own fast path)


class _Reference(SimulatedController):
    """Computes every reply afresh: a value() of its own means nothing is kept."""

    def value(self, kind, index):
        return super().value(kind, index)


def test_kept_replies_are_the_bytes_computed_afresh() -> None:
    """One request in flight (each read one whole request: the kept-reply path), GETs
    repeated around PUTs, errors and moving values: the same bytes as computing each."""
    lines = [
        f"GET:RC8:{n}:{t}:".encode() for n in (1, 2, 10, 99, 100) for t in ("I", "P", "S", "IO")
    ]
    lines += [
        b"GET:RC8:0:I:",
        b"GET:RC8:0:P:",
        b" \tGET:RC8:2:P:",
        b"get:rc8:3:f:",
        b"GET:RC8:x:I:",
    ]
    puts = [b"PUT:RC8:10:I:3,7", b"PUT:RC8:1:P:bad", b"PUT:RC8:2:S:8,changed", b"PUT:RC8:0:I:3,1"]
    script = [*lines, puts[0], *lines, puts[1], *lines, puts[2], *lines, puts[3], *lines]
    reference = _Reference(clock=lambda: 0.0)
    expected = [reference.handle(line)[0].decode("ascii")[:-1] for line in script]

    async def scenario(sim: SimulatorServer) -> list[str]:
        line = await connect(sim)
        return [await line.ask(request + b"\r") for request in script]

    controller = SimulatedController(clock=lambda: 0.0)
    assert run(scenario, controller) == expected
    assert controller.known_frames  # the path under test was taken
    assert controller.requests == len(script)


def test_a_kept_request_after_half_a_line_is_part_of_that_line() -> None:
    async def scenario(sim: SimulatorServer) -> list[str]:
        line = await connect(sim)
        first = await line.ask(b"GET:RC8:10:I:\r")  # now kept
        line.writer.write(b"GET:RC8:10:I:")
        await line.writer.drain()
        await asyncio.sleep(0.05)  # two reads: the second alone is a kept request
        return [first, await line.ask(b"GET:RC8:10:I:\r"), await line.ask(b"GET:RC8:10:I:\r")]

    first, joined, again = run(scenario)
    assert first == again == "0,3,0"
    assert code(joined) == hresult.E_INVALIDCOMMAND


def test_kept_replies_give_way_to_faults_turned_on_and_to_a_value_of_a_test() -> None:
    async def scenario(sim: SimulatorServer) -> list[str]:
        line = await connect(sim)
        replies = [await line.ask(b"GET:RC8:1:S:\r"), await line.ask(b"GET:RC8:1:S:\r")]
        replies.append(await line.ask(b"SIM:SET:error_rate=1\r"))
        replies += [await line.ask(b"GET:RC8:1:S:\r") for _ in range(2)]
        other = await connect(sim)  # a session that never had a fault queue of its own
        replies += [await other.ask(b"GET:RC8:1:S:\r") for _ in range(2)]
        return replies

    replies = run(scenario)
    assert replies[:3] == ["0,8,RC8 simulator", "0,8,RC8 simulator", "0"]
    assert all(code(reply) != 0 for reply in replies[3:])

    counting = SimulatedController()
    counting.value = lambda kind, index: counting.requests  # type: ignore[method-assign]

    async def counted(sim: SimulatorServer) -> list[str]:
        line = await connect(sim)
        return [await line.ask(b"GET:RC8:10:I:\r") for _ in range(3)]

    assert run(counted, counting) == ["0,3,1", "0,3,2", "0,3,3"]
    assert not counting.known_frames


def test_kept_replies_stay_bounded() -> None:
    from rac_console.sim.controller import MAX_CACHED

    controller = SimulatedController()
    for n in range(3 * MAX_CACHED):
        controller.handle(f"GET:RC8:{n % 100}:{'IFDS'[n // 100 % 4]}:{' ' * (n // 400)}".encode())
    assert 0 < len(controller.known_frames) <= MAX_CACHED


def test_simulator_refuses_strings_it_could_not_send_back() -> None:
    controller = SimulatedController()
    reply, _ = controller.handle(b"PUT:RC8:5:S:8,a\nb")
    assert reply == f"{E_INVALIDARG - 2**32}\r".encode()
    assert controller.handle(b"GET:RC8:5:S:")[0] == b"0,8,\r"
