"""One simulator session: a client connection served through an asyncio transport.

Over 300 lines on purpose: the fast path, the fault queue and the limits that bound
what a client can cost are one connection's life, read together.

Without faults every reply is written as its request is read (the fast path). A read
that is one GET answered before, with no PUT since, is answered from the controller's
kept replies without being split or parsed. With faults configured, each session's
requests go through a bounded queue served by one task, so replies can be delayed,
split, dropped or garbled in order. An extra line with a gap is sent by a timer of its
own, so it can land while later requests are in flight.

On Linux a session starts in the server's :class:`~.lane.FastLane`, with no transport:
the lane serves the plain path itself and hands the session over (``adopt``) with what
it still owes when it needs more than that: faults, a transcript, a client that does
not read its replies. What a session needs of its server and of the lane is said here
(:class:`Host`, :class:`Lane`): the server imports the lane and this module, the lane
this module, and this module neither of them.

A session reads at most ``READ_SIZE`` bytes at a time, and stops reading while its
client leaves more than ``WRITE_HIGH`` bytes of replies unread, or while its fault
queue is full; requests read but not yet answered wait as raw bytes (one read's worth).
Nothing is written to a connection that is closing (asyncio would warn on stderr).
"""

from __future__ import annotations

import asyncio
import socket
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Protocol

from ..protocol import FrameTooLong, LineDecoder
from ..protocol.hresult import E_INVALIDRCVPACKET
from .controller import MAX_REQUEST, SimulatedController, code_reply
from .faults import EXTRA_LINE, GARBAGE, FaultPlan
from .replay import ReplayController

CONTROL_PREFIX = b"SIM:"
CR = b"\r"
QUEUE_HIGH, QUEUE_LOW = 64, 16
SPLIT_PAUSE = 0.001
READ_SIZE = 1024  # bytes read from a client at a time: about 70 requests
WRITE_HIGH = 16 * 1024  # unread replies over this: stop reading that client
WRITE_BATCH = 4096  # the fast path writes the replies to one read in pieces this big


@dataclass
class Owed:
    """What the fast lane leaves a session it hands over: the end of a reply its client
    has not taken yet (then, in ``held``, the lines still to answer), or a read not
    answered at all (faults came on), and whether the session ends once that is sent."""

    unsent: bytes = b""
    read: bytes | None = None
    close: bool = False
    abort: bool = False  # the server closed it on the way (stopping)


class Host(Protocol):
    """What a session needs of its server (:class:`~.server.SimulatorServer`)."""

    sessions: set[SimSession]
    refused: int
    numbers: Iterator[int]  # each new session's number, 1 the first
    fast_frames: dict[bytes, bytes]
    control_lines: bool

    @property
    def controller(self) -> SimulatedController | ReplayController: ...
    @property
    def plan(self) -> FaultPlan: ...
    def full(self) -> bool: ...
    def answer(self, line: bytes) -> tuple[bytes, bool]: ...
    def note(self, session: int, line: bytes, reply: bytes | None = None) -> int: ...
    def sent(self, entry: int, reply: bytes) -> None: ...
    def control(self, line: bytes) -> bytes: ...
    def forget(self, session: SimSession) -> None: ...


class Lane(Protocol):
    """What a session needs of the lane serving it (:class:`~.lane.FastLane`)."""

    def drop(self, session: SimSession) -> None: ...


class SimSession(asyncio.BufferedProtocol):
    """One client connection. It reads into a small buffer of its own and stops reading
    while its client does not read (or its fault queue is full), so no client can make
    the server buffer, or compute replies, without bound. ``sock`` and ``lane`` are set
    while the fast lane serves it (then it has no transport)."""

    def __init__(self, server: Host, sock: socket.socket | None = None) -> None:
        self._server = server
        self.number = next(server.numbers)
        self.sock = sock
        self.lane: Lane | None = None
        self._owed: Owed | None = None  # set when the lane hands it over
        self.connected = False  # connection_made has run: it has (or had) a transport
        self._decoder = LineDecoder(MAX_REQUEST - 1)
        self.partial = False  # the decoder holds the start of a line
        self._transport: asyncio.Transport | None = None
        self._view: memoryview | None = None  # the read buffer, made on the first read
        self._queue: asyncio.Queue[tuple[bytes | None, int]] | None = None
        self._task: asyncio.Task[None] | None = None
        self._held: bytes | None = None  # lines read, not yet answered or queued; CR after each
        self._held_too_long = False  # and after them, a request over 256 bytes to refuse
        self._writing_paused = False
        self._reading_paused = False
        self._writable: asyncio.Event | None = None  # the fault path waits on it while paused
        self._answering = False
        self.last_active = time.monotonic()
        self._extra_timers: set[asyncio.TimerHandle] = set()
        self._mid_reply = False  # a split reply is going out: an extra line must wait
        self._held_extras = 0

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.connected = True
        server, owed = self._server, self._owed
        if owed is None and server.full():  # one the lane hands over is counted already
            server.refused += 1
            transport.abort()  # type: ignore[attr-defined]
            return
        self._transport = transport  # type: ignore[assignment]
        self._transport.set_write_buffer_limits(high=WRITE_HIGH)  # type: ignore[union-attr]
        server.sessions.add(self)
        if owed is not None:
            self._owed, self.sock = None, None
            self._settle(owed)

    def hand_over(self, owed: Owed, lines: list[bytes], too_long: bool) -> None:
        """Leave the lane: ``owed`` and then ``lines`` (and a request over 256 bytes, if
        ``too_long``) are answered once a transport is made for it (``connection_made``)."""
        self.lane, self._owed = None, owed
        if lines or too_long:
            self._hold(lines, too_long)

    def _settle(self, owed: Owed) -> None:
        """Pay what the lane left: the end of a reply, then the lines held, or a read."""
        transport = self._transport
        assert transport is not None
        if owed.abort:
            transport.abort()
            return
        if owed.unsent:
            transport.write(owed.unsent)
        if owed.close:
            transport.close()
        elif owed.read is not None:
            self.feed(owed.read)
        else:
            self._release()

    def connection_lost(self, exc: Exception | None) -> None:
        self._server.forget(self)
        self.sock, self.lane = None, None
        self._transport = None
        self._view = None
        self._held = None
        if self._task is not None:
            self._task.cancel()
        for timer in self._extra_timers:
            timer.cancel()

    def idle_for(self, now: float) -> float:
        """Seconds since the client last sent or read anything; 0 while a reply is due."""
        queued = self._queue is not None and self._queue.qsize()
        if self._answering or queued or self._owed is not None:
            return 0.0
        return now - self.last_active

    # ---------------------------------------------------------------- reading

    def get_buffer(self, sizehint: int) -> memoryview:
        if self._view is None:  # idle sessions never make one
            self._view = memoryview(bytearray(READ_SIZE))
        return self._view

    def buffer_updated(self, nbytes: int) -> None:
        transport, view = self._transport, self._view
        if transport is None or view is None or transport.is_closing():
            return
        self.last_active = time.monotonic()
        data = view[:nbytes].tobytes()
        # The fast path's own fast path: this read is one whole request whose reply is
        # kept (a kept GET line holds no CR or LF), and nothing came before it that waits
        # or is half read. It answers as _take would, without splitting or parsing.
        reply = self._server.fast_frames.get(data)
        if (
            reply is not None
            and not self.partial
            and self._held is None
            and self._queue is None
            and not self._writing_paused
        ):
            self._server.controller.requests += 1
            transport.write(reply)
            return
        self.feed(data)

    def feed(self, data: bytes) -> None:
        """Answer or queue the requests in one read."""
        lines, too_long = self.decode(data)
        self._take(lines, too_long)

    def decode(self, data: bytes) -> tuple[list[bytes], bool]:
        """The whole lines in ``data`` (after what came before), and whether a line grew
        past 256 bytes (the session is to end after those lines)."""
        try:
            lines, too_long = self._decoder.feed(data), False
        except FrameTooLong as exc:
            lines, too_long = exc.lines, True
        self.partial = bool(self._decoder.pending)
        return lines, too_long

    def _take(self, lines: list[bytes], too_long: bool) -> None:
        """Answer (fast path) or queue (fault path) ``lines`` in order, until the client
        stops reading its replies or the queue is full; then keep the rest, and stop
        reading, until it is their turn. A request over 256 bytes ends the session."""
        transport = self._transport
        if transport is None or transport.is_closing():
            return
        if self._held is not None:  # a transport that fed us while paused: keep the order
            if self._held_too_long:
                return
            lines = self._held.split(CR)[:-1] + lines
            self._held = None
        server = self._server
        if self._queue is not None or server.plan.active:
            self._take_faulty(lines, too_long)
            return
        n, count = 0, len(lines)
        while n < count:  # replies go out in writes of up to WRITE_BATCH bytes
            if self._writing_paused:
                self._hold(lines[n:], too_long)
                return
            replies: list[bytes] = []
            size, close = 0, False
            while n < count and size < WRITE_BATCH and not close:
                reply, close = server.answer(lines[n])
                server.note(self.number, lines[n], reply)
                replies.append(reply)
                size += len(reply)
                n += 1
            transport.write(replies[0] if len(replies) == 1 else b"".join(replies))
            if close or transport.is_closing():
                transport.close()
                return
        if too_long:
            transport.write(code_reply(E_INVALIDRCVPACKET))
            transport.close()

    def _hold(self, lines: list[bytes], too_long: bool) -> None:
        self._held = b"".join(line + CR for line in lines)
        self._held_too_long = too_long
        self._update_reading()

    def _release(self) -> None:
        """Take the held lines again (the client read, or the queue emptied)."""
        if self._held is not None:
            held, too_long = self._held, self._held_too_long
            self._held, self._held_too_long = None, False
            self._take(held.split(CR)[:-1], too_long)
        self._update_reading()

    def _update_reading(self) -> None:
        """Read only while nothing is held and the client reads its replies."""
        transport = self._transport
        if transport is None or transport.is_closing():
            return
        stop = self._held is not None or self._writing_paused
        if stop != self._reading_paused:
            self._reading_paused = stop
            if stop:
                transport.pause_reading()
            else:
                transport.resume_reading()

    def eof_received(self) -> bool | None:
        """A half-closed client still gets the answers to what it sent."""
        if self._queue is None:
            return None  # the fast path has answered everything already
        self._queue.put_nowait((None, -1))
        return True

    # ------------------------------------------------------------ flow control

    def pause_writing(self) -> None:
        self._writing_paused = True
        self._update_reading()

    def resume_writing(self) -> None:
        self._writing_paused = False
        self.last_active = time.monotonic()
        if self._writable is not None:
            self._writable.set()
            self._writable = None
        self._release()

    def abort(self) -> None:
        if self._transport is not None:
            self._transport.abort()
        elif self.lane is not None:
            self.lane.drop(self)
        elif self._owed is not None:  # on its way from the lane to a transport
            self._owed.abort = True

    def close_idle(self) -> None:
        """Close a session idle too long: politely, unless replies wait unread."""
        if self.lane is not None:  # the lane never keeps a reply unsent
            self.lane.drop(self)
            return
        transport = self._transport
        if transport is None or transport.is_closing():
            return
        if transport.get_write_buffer_size():
            transport.abort()
        else:
            transport.close()

    # ----------------------------------------------------------- faulty path

    def _take_faulty(self, lines: list[bytes], too_long: bool) -> None:
        if self._queue is None:
            self._queue = asyncio.Queue()
            self._task = asyncio.get_running_loop().create_task(self._serve_queue())
        server, queue = self._server, self._queue
        for n, line in enumerate(lines):
            if queue.qsize() >= QUEUE_HIGH:
                self._hold(lines[n:], too_long)
                return
            queue.put_nowait((line, server.note(self.number, line)))
        if too_long:
            queue.put_nowait((CR, server.note(self.number, b"")))  # CR: the too-long marker

    async def _serve_queue(self) -> None:
        assert self._queue is not None
        queue = self._queue
        while True:
            line, entry = await queue.get()
            transport = self._transport
            if transport is None or transport.is_closing():
                return
            if self._held is not None and queue.qsize() < QUEUE_LOW:
                self._release()
            if line is None:  # the client half-closed: all answered, now close
                transport.close()
                return
            if self._writing_paused:  # the client is not reading: wait until it does
                self._writable = self._writable or asyncio.Event()
                await self._writable.wait()
                transport = self._transport
                if transport is None or transport.is_closing():
                    return
            if line == CR:
                transport.write(code_reply(E_INVALIDRCVPACKET))
                transport.close()
                return
            if self._server.control_lines and line.startswith(CONTROL_PREFIX):
                transport.write(self._server.control(line))
                continue
            self._answering = True
            try:
                if not await self._answer_with_fault(transport, line, entry):
                    return
            finally:
                self._answering = False
                self.last_active = time.monotonic()

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
            reply = code_reply(fault.error_code)
        server.sent(entry, reply)
        # Without a gap the extra line goes out with the reply's end, in the same write.
        tail = EXTRA_LINE if fault.extra and fault.extra_gap is None else b""
        if not await self._write_reply(transport, reply, fault.split, tail):
            return False
        if fault.extra_gap == 0:
            self._write_extra()  # straight after, but a write (a TCP segment) of its own
        elif fault.extra_gap is not None:
            self._write_extra_later(fault.extra_gap)
        if close or transport.is_closing():
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
