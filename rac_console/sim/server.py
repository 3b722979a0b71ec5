"""The simulator's asyncio TCP server: many sessions over one SimulatedController.

Over 450 lines on purpose: the fast path, the fault queue and the limits that bound
what a client can cost are one connection's life, read together.

Without faults every reply is written as its request is read (the fast path). A read
that is one GET answered before, with no PUT since, is answered from the controller's
kept replies without being split or parsed: that is what a polling client sends, and
then asyncio itself is most of what a request costs. With faults configured, each
session's requests go through a bounded queue served by one task, so replies can be
delayed, split, dropped or garbled in order. An extra line with a gap is sent by a
timer of its own, so it can land while later requests are in flight.

What a client can cost the simulator is bounded, whatever it does (README, Reliability):

- A session reads at most ``READ_SIZE`` bytes at a time, and stops reading while its
  client leaves more than ``WRITE_HIGH`` bytes of replies unread, or while its fault
  queue is full; requests read but not yet answered wait as raw bytes (one read's worth).
  So a client that never reads holds a few KiB, and every other client takes its turn.
- Each connection's OS buffers are capped at ``SOCKET_BUFFER`` bytes each way, so a
  client that never reads cannot have megabytes of replies computed for it.
- Nothing is written to a connection that is closing (asyncio would warn on stderr).
- Accepting is a loop of our own: out of file descriptors, the session idle longest is
  closed to take the new client (or, none idle, new clients wait), with one line said.
- What the user should hear goes through :class:`Notices`: a line at once, then at most
  one summary per kind per 10 s.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import ipaddress
import itertools
import os
import socket
import time
from collections.abc import Callable

from ..protocol import FrameTooLong, LineDecoder
from ..protocol.hresult import E_INVALIDARG, E_INVALIDCOMMAND, E_INVALIDRCVPACKET
from .controller import MAX_REQUEST, SimulatedController, _reply
from .faults import EXTRA_LINE, GARBAGE, FaultPlan, FaultSettings
from .notices import Notices
from .replay import ReplayController

LOOPBACK = "127.0.0.1"
CONTROL_PREFIX = b"SIM:"
CR = b"\r"
QUEUE_HIGH, QUEUE_LOW = 64, 16
SPLIT_PAUSE = 0.001
READ_SIZE = 1024  # bytes read from a client at a time: about 70 requests
WRITE_HIGH = 16 * 1024  # unread replies over this: stop reading that client
WRITE_BATCH = 4096  # the fast path writes the replies to one read in pieces this big
SOCKET_BUFFER = 16 * 1024  # SO_SNDBUF and SO_RCVBUF of each connection (Linux doubles it)
BACKLOG = 1024
SHED_AFTER_IDLE = 1.0  # out of descriptors, only a session idle this long is closed
ACCEPT_RETRY_MAX = 1.0
#: accept() errors that mean "out of descriptors or memory": shed a session, or wait.
RESOURCE_ERRORS = {
    code
    for name in ("EMFILE", "ENFILE", "ENOBUFS", "ENOMEM", "WSAEMFILE", "WSAENOBUFS")
    if (code := getattr(errno, name, None)) is not None
}


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class _SimSession(asyncio.BufferedProtocol):
    """One client connection. It reads into a small buffer of its own and stops reading
    while its client does not read (or its fault queue is full), so no client can make
    the server buffer, or compute replies, without bound."""

    def __init__(self, server: SimulatorServer) -> None:
        self._server = server
        self.number = next(server._numbers)
        self._decoder = LineDecoder(MAX_REQUEST - 1)
        self._partial = False  # the decoder holds the start of a line
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
        server = self._server
        limit = server.plan.settings.max_sessions
        if limit and len(server.sessions) >= limit:
            server.refused += 1
            transport.abort()  # type: ignore[attr-defined]
            return
        self._transport = transport  # type: ignore[assignment]
        self._transport.set_write_buffer_limits(high=WRITE_HIGH)  # type: ignore[union-attr]
        server.sessions.add(self)

    def connection_lost(self, exc: Exception | None) -> None:
        self._server.sessions.discard(self)
        self._server._shedding.discard(self)
        self._transport = None
        self._view = None
        self._held = None
        if self._task is not None:
            self._task.cancel()
        for timer in self._extra_timers:
            timer.cancel()

    def idle_for(self, now: float) -> float:
        """Seconds since the client last sent or read anything; 0 while a reply is due."""
        if self._answering or (self._queue is not None and self._queue.qsize()):
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
            and not self._partial
            and self._held is None
            and self._queue is None
            and not self._writing_paused
        ):
            self._server.controller.requests += 1
            transport.write(reply)
            return
        try:
            lines, too_long = self._decoder.feed(data), False
        except FrameTooLong as exc:
            lines, too_long = exc.lines, True
        self._partial = bool(self._decoder.pending)
        self._take(lines, too_long)

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
            transport.write(_reply(E_INVALIDRCVPACKET))
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

    def close_idle(self) -> None:
        """Close a session idle too long: politely, unless replies wait unread."""
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
                transport.write(_reply(E_INVALIDRCVPACKET))
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


class SimulatorServer:
    """``async with SimulatorServer() as sim:`` serves on ``sim.host:sim.port``.

    ``transcript=True`` keeps every (session, request, reply sent) for tests that
    check what crossed the wire, in the order requests arrived; a reply never sent
    (dropped, stalled, or its connection closed first) is ``None``. The controller and
    the transcript are fixed once made; faults change through ``plan`` or ``set_faults``.
    ``idle_timeout`` (seconds, 0: never) closes sessions idle that long; ``control=False``
    answers ``SIM:`` lines like any unknown command; ``notify`` receives the lines a
    user should read (rate-limited; none are shown without it).
    """

    def __init__(
        self,
        host: str = LOOPBACK,
        port: int = 0,
        controller: SimulatedController | ReplayController | None = None,
        faults: FaultSettings | None = None,
        transcript: bool = False,
        *,
        idle_timeout: float = 0.0,
        control: bool = True,
        notify: Callable[[str], None] | None = None,
    ) -> None:
        self.host = host
        self.port = port
        #: A replay's answers move on with each request: it keeps none for the fast path.
        self.controller = controller or SimulatedController()
        self.transcript: list[tuple[int, bytes, bytes | None]] | None = [] if transcript else None
        #: Request frames the sessions answer at once, from the controller's kept replies:
        #: none while faults are on or a transcript is kept (both need each request seen).
        self.fast_frames: dict[bytes, bytes] = {}
        self.plan = FaultPlan(faults or FaultSettings())
        self.sessions: set[_SimSession] = set()
        self.refused = 0
        self.shed = 0  # sessions closed to take a client when out of descriptors
        self.timed_out = 0  # sessions closed by idle_timeout
        self.idle_timeout = idle_timeout
        self.control_lines = control
        self.notices = Notices(notify or _nobody, schedule=self._later)
        self._numbers = itertools.count(1)
        self._sockets: list[socket.socket] = []
        self._accepting: list[asyncio.Task[None]] = []
        self._connecting: set[asyncio.Task[None]] = set()
        self._timers: set[asyncio.TimerHandle] = set()
        self._shedding: set[_SimSession] = set()
        self._stopped: asyncio.Event | None = None

    @property
    def plan(self) -> FaultPlan:
        return self._plan

    @plan.setter
    def plan(self, plan: FaultPlan) -> None:
        self._plan = plan
        plain = self.transcript is None and not plan.active
        self.fast_frames = self.controller.known_frames if plain else {}

    def set_faults(self, settings: FaultSettings) -> None:
        settings.check()
        self.plan = FaultPlan(settings)

    def answer(self, line: bytes) -> tuple[bytes, bool]:
        """The fast path's answer, control lines included."""
        if self.control_lines and line.startswith(CONTROL_PREFIX):
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
        self.controller.forget()  # kept replies start afresh after any SIM: line
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

    # ------------------------------------------------------------- serving

    async def start(self) -> SimulatorServer:
        loop = asyncio.get_running_loop()
        self._sockets = await _listen(loop, self.host, self.port)
        self.port = self._sockets[0].getsockname()[1]
        self._stopped = asyncio.Event()
        self._accepting = [loop.create_task(self._accept(sock)) for sock in self._sockets]
        if self.idle_timeout > 0:
            self._later(self._sweep_period(), self._sweep)
        return self

    async def stop(self) -> None:
        for task in [*self._accepting, *self._connecting]:
            task.cancel()
        await asyncio.gather(*self._accepting, *self._connecting, return_exceptions=True)
        self._accepting = []
        for sock in self._sockets:
            sock.close()
        self._sockets = []
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()
        for session in list(self.sessions):
            session.abort()
        for _ in range(100):  # their connection_lost runs on the next passes of the loop
            if not self.sessions:
                break
            await asyncio.sleep(0)
        if self._stopped is not None:
            self._stopped.set()

    async def serve_forever(self) -> None:
        assert self._stopped is not None, "start() first"
        await self._stopped.wait()

    async def __aenter__(self) -> SimulatorServer:
        return await self.start()

    async def __aexit__(self, *exc_info: object) -> None:
        await self.stop()

    async def _accept(self, listener: socket.socket) -> None:
        """Take clients one at a time, calmly whatever accept() says."""
        loop = asyncio.get_running_loop()
        backoff = 0.0
        while True:
            try:
                conn, _ = await loop.sock_accept(listener)
            except OSError as exc:
                if exc.errno in RESOURCE_ERRORS:
                    backoff = await self._out_of_descriptors(backoff)
                elif not isinstance(exc, ConnectionError):  # ConnectionError: client gone
                    self.notices.note("accept", f"cannot accept a client: {_reason(exc)}")
                    await asyncio.sleep(0.1)
                continue
            backoff = 0.0
            task = loop.create_task(self._take_client(loop, conn))  # and accept the next
            self._connecting.add(task)
            task.add_done_callback(self._connecting.discard)

    async def _take_client(self, loop: asyncio.AbstractEventLoop, conn: socket.socket) -> None:
        try:
            conn.setblocking(False)
            await loop.connect_accepted_socket(lambda: _SimSession(self), conn)
        except Exception as exc:  # that client only: the others go on being served
            conn.close()
            if not isinstance(exc, ConnectionError):
                self.notices.note("accept", f"cannot take a client: {exc!r}")

    async def _out_of_descriptors(self, backoff: float) -> float:
        """Close the session idle longest so the waiting client can be taken; with none
        idle, new clients wait (in the OS's queue) and accept is tried again later."""
        if self._shedding:  # one is closing already: its descriptor is not free yet
            await asyncio.sleep(0.01)
            return backoff
        now = time.monotonic()
        idle = [s for s in self.sessions if s.idle_for(now) >= SHED_AFTER_IDLE]
        if idle:
            victim = min(idle, key=lambda s: s.last_active)
            self.shed += 1
            self.notices.note(
                "shed",
                f"out of file descriptors with {len(self.sessions)} sessions open: closing "
                "the session idle longest for each new client (raise the limit, e.g. "
                "ulimit -n, or use --idle-timeout)",
            )
            self._shedding.add(victim)
            victim.abort()
            await asyncio.sleep(0)  # its socket closes on the next pass of the loop
            return 0.0
        self.notices.note(
            "full",
            f"out of file descriptors, no session idle for {SHED_AFTER_IDLE:g} s: new "
            "clients wait (raise the limit, e.g. ulimit -n)",
        )
        backoff = min(max(backoff * 2, 0.05), ACCEPT_RETRY_MAX)
        await asyncio.sleep(backoff)
        return backoff

    def _sweep_period(self) -> float:
        return min(max(self.idle_timeout / 4, 0.05), 1.0)

    def _sweep(self) -> None:
        """Close the sessions idle for idle_timeout; then again in a while."""
        now = time.monotonic()
        for session in [s for s in self.sessions if s.idle_for(now) >= self.idle_timeout]:
            self.timed_out += 1
            session.close_idle()
        self._later(self._sweep_period(), self._sweep)

    def _later(self, delay: float, callback: Callable[[], None]) -> None:
        """``callback`` in ``delay`` seconds, unless the server stops first."""

        def fire() -> None:
            self._timers.discard(handle)
            callback()

        try:
            handle = asyncio.get_running_loop().call_later(delay, fire)
        except RuntimeError:  # no loop running (stopped): nothing left to do later
            return
        self._timers.add(handle)


async def _listen(loop: asyncio.AbstractEventLoop, host: str, port: int) -> list[socket.socket]:
    """Listening sockets on every address of ``host``, as ``loop.create_server`` makes
    them, with each connection's OS buffers capped (accepted sockets inherit them)."""
    infos = await loop.getaddrinfo(
        host or None, port, family=socket.AF_UNSPEC, type=socket.SOCK_STREAM,
        flags=socket.AI_PASSIVE,
    )  # fmt: skip
    sockets: list[socket.socket] = []
    try:
        for family, kind, proto, _, address in dict.fromkeys(infos):
            sock = socket.socket(family, kind, proto)
            sockets.append(sock)
            if os.name == "posix":  # on Windows this would let another process take the port
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if family == socket.AF_INET6 and hasattr(socket, "IPPROTO_IPV6"):
                sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
            for option in (socket.SO_SNDBUF, socket.SO_RCVBUF):
                with contextlib.suppress(OSError):  # a platform that will not: its defaults
                    sock.setsockopt(socket.SOL_SOCKET, option, SOCKET_BUFFER)
            sock.bind(address)
            sock.listen(BACKLOG)
            sock.setblocking(False)
    except BaseException:
        for sock in sockets:
            sock.close()
        raise
    if not sockets:
        raise OSError(f"no address to listen on for {host!r}")
    return sockets


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc) or type(exc).__name__


def _nobody(line: str) -> None:
    """Where notices go when no one asked for them (the in-process simulator)."""
