"""The simulator's asyncio TCP server: many sessions over one SimulatedController.

Without faults every reply is written from ``data_received`` (the fast path). With
faults configured, each session's requests go through a bounded queue served by one
task, so replies can be delayed, split, dropped or garbled in order. An extra line with
a gap is sent by a timer of its own, so it can land while later requests are in flight.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import itertools

from ..protocol import FrameTooLong, LineDecoder
from ..protocol.hresult import E_INVALIDARG, E_INVALIDCOMMAND, E_INVALIDRCVPACKET
from .controller import MAX_REQUEST, SimulatedController, _reply
from .faults import EXTRA_LINE, GARBAGE, FaultPlan, FaultSettings

LOOPBACK = "127.0.0.1"
CONTROL_PREFIX = b"SIM:"
QUEUE_HIGH, QUEUE_LOW = 64, 16
SPLIT_PAUSE = 0.001


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class _SimSession(asyncio.Protocol):
    """One client connection. Reading pauses while the client is not reading, and while
    its queue is long, so no client can make the server buffer without bound."""

    def __init__(self, server: SimulatorServer) -> None:
        self._server = server
        self.number = next(server._numbers)
        self._decoder = LineDecoder(MAX_REQUEST - 1)
        self._transport: asyncio.Transport | None = None
        self._queue: asyncio.Queue[tuple[bytes | None, int]] | None = None
        self._task: asyncio.Task[None] | None = None
        self._reading_paused = False
        self._extra_timers: set[asyncio.TimerHandle] = set()
        self._mid_reply = False  # a split reply is going out: an extra line must wait
        self._held_extras = 0

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        server = self._server
        limit = server.plan.settings.max_sessions
        if limit and len(server.sessions) >= limit:
            server.refused += 1
            transport.abort()  # type: ignore[attr-defined]
            return
        self._transport = transport  # type: ignore[assignment]
        server.sessions.add(self)

    def connection_lost(self, exc: Exception | None) -> None:
        self._server.sessions.discard(self)
        self._transport = None
        if self._task is not None:
            self._task.cancel()
        for timer in self._extra_timers:
            timer.cancel()

    def data_received(self, data: bytes) -> None:
        transport = self._transport
        if transport is None or transport.is_closing():
            return
        too_long = False
        try:
            lines = self._decoder.feed(data)
        except FrameTooLong as exc:
            lines, too_long = exc.lines, True
        if too_long:
            lines.append(b"")  # a marker: answer E_INVALIDRCVPACKET after the lines before it
        if self._queue is not None or self._server.plan.settings.active:
            self._enqueue(
                [(line, self._server.note(self.number, line)) for line in lines], too_long
            )
            return
        for n, line in enumerate(lines):
            if too_long and n == len(lines) - 1:
                transport.write(_reply(E_INVALIDRCVPACKET))
                transport.close()
                return
            reply, close = self._server.answer(line)
            self._server.note(self.number, line, reply)
            transport.write(reply)
            if close:
                transport.close()
                return

    # ----------------------------------------------------------- faulty path

    def _enqueue(self, lines: list[tuple[bytes, int]], too_long: bool) -> None:
        if self._queue is None:
            self._queue = asyncio.Queue()
            self._task = asyncio.get_running_loop().create_task(self._serve_queue())
        for n, (line, entry) in enumerate(lines):
            marker = too_long and n == len(lines) - 1
            self._queue.put_nowait((b"\r", entry) if marker else (line, entry))
        if self._queue.qsize() > QUEUE_HIGH and self._transport is not None:
            self._transport.pause_reading()
            self._reading_paused = True

    async def _serve_queue(self) -> None:
        assert self._queue is not None
        while True:
            line, entry = await self._queue.get()
            transport = self._transport
            if transport is None or transport.is_closing():
                return
            if line is None:  # the client half-closed: all answered, now close
                transport.close()
                return
            if self._reading_paused and self._queue.qsize() < QUEUE_LOW:
                self._reading_paused = False
                transport.resume_reading()
            if line == b"\r":  # the too-long marker
                transport.write(_reply(E_INVALIDRCVPACKET))
                transport.close()
                return
            if line.startswith(CONTROL_PREFIX):
                transport.write(self._server.control(line))
                continue
            if not await self._answer_with_fault(transport, line, entry):
                return

    async def _answer_with_fault(
        self, transport: asyncio.Transport, line: bytes, entry: int
    ) -> bool:
        """Answer one request through its fault; False when the connection is done."""
        server = self._server
        reply, close = server.controller.handle(line)
        fault = server.plan.next()
        if fault.delay:
            await asyncio.sleep(fault.delay)
            if transport.is_closing():
                return False
        if fault.action == "drop":
            transport.abort()
            return False
        if fault.action == "stall":
            return True
        if fault.action == "garble":
            reply = GARBAGE + b"\r"
        elif fault.action == "error":
            reply = _reply(fault.error_code)
        server.sent(entry, reply)
        # Without a gap the extra line goes out with the reply's end, in the same write.
        tail = EXTRA_LINE if fault.extra and fault.extra_gap is None else b""
        if not await self._write_reply(transport, reply, fault.split, tail):
            return False
        if fault.extra_gap == 0:
            self._write_extra()  # straight after, but a write (a TCP segment) of its own
        elif fault.extra_gap is not None:
            self._write_extra_later(fault.extra_gap)
        if close:
            transport.close()
            return False
        return True

    async def _write_reply(
        self, transport: asyncio.Transport, reply: bytes, split: bool, tail: bytes
    ) -> bool:
        """Write one reply (in 2-byte pieces when split) with ``tail`` in its last write;
        False if the connection closed on the way."""
        pieces = [reply[i : i + 2] for i in range(0, len(reply), 2)] if split else [reply]
        self._mid_reply = True
        try:
            for piece in pieces[:-1]:
                transport.write(piece)
                await asyncio.sleep(SPLIT_PAUSE)
                if transport.is_closing():
                    return False
            transport.write(pieces[-1] + tail)
        finally:
            self._mid_reply = False
        self._flush_held_extras()
        return True

    def _write_extra_later(self, gap: float) -> None:
        """The extra line ``gap`` seconds from now, whatever this session does meanwhile."""

        def fire() -> None:
            self._extra_timers.discard(timer)
            self._write_extra()

        timer = asyncio.get_running_loop().call_later(gap, fire)
        self._extra_timers.add(timer)

    def _write_extra(self) -> None:
        """One extra line as a write of its own; held while a split reply is half out."""
        transport = self._transport
        if transport is None or transport.is_closing():
            return
        if self._mid_reply:
            self._held_extras += 1  # a line spliced into a reply would be another fault
            return
        transport.write(EXTRA_LINE)

    def _flush_held_extras(self) -> None:
        held, self._held_extras = self._held_extras, 0
        for _ in range(held):
            self._write_extra()

    def eof_received(self) -> bool | None:
        """A half-closed client still gets the answers to what it sent."""
        if self._queue is None:
            return None  # the fast path has answered everything already
        self._queue.put_nowait((None, -1))
        return True

    # ------------------------------------------------------------ flow control

    def pause_writing(self) -> None:
        if self._transport is not None:
            self._transport.pause_reading()

    def resume_writing(self) -> None:
        if self._transport is not None and not self._transport.is_closing():
            self._transport.resume_reading()

    def abort(self) -> None:
        if self._transport is not None:
            self._transport.abort()


class SimulatorServer:
    """``async with SimulatorServer() as sim:`` serves on ``sim.host:sim.port``.

    ``transcript=True`` keeps every (session, request, reply sent) for tests that
    check what crossed the wire, in the order requests arrived; a reply never sent
    (dropped, stalled, or its connection closed first) is ``None``.
    """

    def __init__(
        self,
        host: str = LOOPBACK,
        port: int = 0,
        controller: SimulatedController | None = None,
        faults: FaultSettings | None = None,
        transcript: bool = False,
    ) -> None:
        self.host = host
        self.port = port
        self.controller = controller or SimulatedController()
        self.plan = FaultPlan(faults or FaultSettings())
        self.sessions: set[_SimSession] = set()
        self.refused = 0
        self.transcript: list[tuple[int, bytes, bytes | None]] | None = [] if transcript else None
        self._numbers = itertools.count(1)
        self._server: asyncio.Server | None = None

    def set_faults(self, settings: FaultSettings) -> None:
        settings.check()
        self.plan = FaultPlan(settings)

    def answer(self, line: bytes) -> tuple[bytes, bool]:
        """The fast path's answer, control lines included."""
        if line.startswith(CONTROL_PREFIX):
            return self.control(line), False
        return self.controller.handle(line)

    def note(self, session: int, line: bytes, reply: bytes | None = None) -> int:
        """Note a request as it arrives (and its reply if already sent); its entry number."""
        if self.transcript is None:
            return -1
        self.transcript.append((session, line, reply))
        return len(self.transcript) - 1

    def sent(self, entry: int, reply: bytes) -> None:
        if self.transcript is not None and entry >= 0:
            session, line, _ = self.transcript[entry]
            self.transcript[entry] = (session, line, reply)

    def control(self, line: bytes) -> bytes:
        """``SIM:SET:delay_ms=50,drop_every=7`` and ``SIM:GET:``: change or read faults."""
        text = line.decode("ascii", "replace").strip()
        command = text[len("SIM:") :]
        if command.upper().startswith("SET:"):
            try:
                self.set_faults(self.plan.settings.updated(command[4:]))
            except ValueError:
                return _reply(E_INVALIDARG)
            return b"0\r"
        if command.upper() == "GET:":
            return b"0,8," + self.plan.settings.describe().encode("ascii") + b"\r"
        return _reply(E_INVALIDCOMMAND)

    async def start(self) -> SimulatorServer:
        loop = asyncio.get_running_loop()
        self._server = await loop.create_server(
            lambda: _SimSession(self), self.host, self.port, reuse_address=True, backlog=1024
        )
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
            for session in list(self.sessions):
                session.abort()
            with contextlib.suppress(Exception):
                await asyncio.wait_for(self._server.wait_closed(), 2)
            self._server = None

    async def serve_forever(self) -> None:
        assert self._server is not None
        await self._server.serve_forever()

    async def __aenter__(self) -> SimulatorServer:
        return await self.start()

    async def __aexit__(self, *exc_info: object) -> None:
        await self.stop()
