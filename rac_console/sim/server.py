"""The simulator's asyncio TCP server: many sessions over one SimulatedController.

Each connection is a :class:`~.session.SimSession`: the fast path (every reply written
as its request is read), the fault queue and the flow control are there. On Linux a
new client is served by the :class:`~.lane.FastLane` (an epoll set of our own, read in
one callback) while nothing but the plain path is needed; the rest of the time, and
elsewhere, by an asyncio transport.

What a client can cost the simulator is bounded, whatever it does (README, Reliability):

- A session reads at most ``READ_SIZE`` bytes at a time, and stops reading while its
  client leaves more than ``WRITE_HIGH`` bytes of replies unread, or while its fault
  queue is full; requests read but not yet answered wait as raw bytes (one read's worth).
  So a client that never reads holds a few KiB, and every other client takes its turn.
  (The lane sends one read's replies at a time and hands a client that does not take
  them to a transport, which then paces it.)
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
import functools
import ipaddress
import itertools
import os
import socket
import time
from collections.abc import Callable, Iterator

from ..protocol.hresult import E_INVALIDARG, E_INVALIDCOMMAND
from .controller import SimulatedController, code_reply
from .faults import FaultPlan, FaultSettings
from .lane import FastLane
from .notices import Notices
from .replay import ReplayController
from .session import CONTROL_PREFIX, SimSession

LOOPBACK = "127.0.0.1"
#: A client's connection, as :meth:`SimulatorServer.connect` hands it out.
Connection = socket.socket
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


class SimulatorServer:
    """``async with SimulatorServer() as sim:`` serves on ``sim.host:sim.port``.

    ``transcript=True`` keeps every (session, request, reply sent) for tests that
    check what crossed the wire, in the order requests arrived; a reply never sent
    (dropped, stalled, or its connection closed first) is ``None``. The controller and
    the transcript are fixed once made; faults change through ``plan`` or ``set_faults``.
    ``idle_timeout`` (seconds, 0: never) closes sessions idle that long; ``control=False``
    answers ``SIM:`` lines like any unknown command; ``notify`` receives the lines a
    user should read (rate-limited; none are shown without it). ``fast_lane=False``
    serves every session through an asyncio transport, as where there is no epoll.
    ``listen=False`` listens on no port: its clients are the connections handed to
    :meth:`take` (one end of a socket pair made in this process), and no one else's.
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
        fast_lane: bool = True,
        listen: bool = True,
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
        self.sessions: set[SimSession] = set()
        self.refused = 0
        self.shed = 0  # sessions closed to take a client when out of descriptors
        self.timed_out = 0  # sessions closed by idle_timeout
        self.idle_timeout = idle_timeout
        self.control_lines = control
        self.notices = Notices(notify or _nobody, schedule=self._later)
        self.numbers: Iterator[int] = itertools.count(1)  # each new session's number
        self._sockets: list[socket.socket] = []
        self._accepting: list[asyncio.Task[None]] = []
        self._connecting: set[asyncio.Task[None]] = set()
        self._timers: set[asyncio.TimerHandle] = set()
        self._shedding: set[SimSession] = set()
        self._stopped: asyncio.Event | None = None
        self._fast_lane = fast_lane
        self._lane: FastLane | None = None
        self._listens = listen
        self._loop: asyncio.AbstractEventLoop | None = None  # serving on it, once started

    @property
    def plan(self) -> FaultPlan:
        return self._plan

    @plan.setter
    def plan(self, plan: FaultPlan) -> None:
        self._plan = plan
        self.fast_frames = self.controller.known_frames if self.plain else {}

    @property
    def plain(self) -> bool:
        """True while every request is answered as it is read: no faults, no transcript."""
        return self.transcript is None and not self._plan.active

    def full(self) -> bool:
        """True when ``max_sessions`` sessions are open: a new client is refused."""
        limit = self._plan.settings.max_sessions
        return bool(limit) and len(self.sessions) >= limit

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
                return code_reply(E_INVALIDARG)
            return b"0\r"
        if command.upper() == "GET:":
            return b"0,8," + self.plan.settings.describe().encode("ascii") + b"\r"
        return code_reply(E_INVALIDCOMMAND)

    # ------------------------------------------------------------- serving

    async def start(self) -> SimulatorServer:
        loop = self._loop = asyncio.get_running_loop()
        if self._listens:
            self._sockets = await _listen(loop, self.host, self.port)
            self.port = self._sockets[0].getsockname()[1]
        self._stopped = asyncio.Event()
        if self._fast_lane:
            self._lane = FastLane.open(self, loop)
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
        if self._lane is not None:
            self._lane.close()
            self._lane = None
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
            if self._lane is not None and self.plain:
                self._admit(self._lane, conn)
                continue
            self._connect(conn, None)  # and accept the next

    def connect(self) -> Connection:
        """(Any thread, once started.) A connection to this simulator that only this
        process holds: one end of a socket pair, the other served as a client (see
        :meth:`take`). ConnectionRefusedError once it has stopped."""
        loop = self._loop
        ours, theirs = socket.socketpair()
        try:
            if loop is None:
                raise RuntimeError("not started")
            loop.call_soon_threadsafe(self.take, theirs)
        except RuntimeError:  # not started, or its loop is closed
            ours.close()
            theirs.close()
            raise ConnectionRefusedError(errno.ECONNREFUSED, "the simulator has stopped") from None
        return ours

    def take(self, conn: socket.socket) -> None:
        """Serve ``conn`` as a client just accepted: a connection made in this process
        (one end of a socket pair), which no port was opened for. On the loop's thread."""
        for option in (socket.SO_SNDBUF, socket.SO_RCVBUF):  # as a listener's clients get
            with contextlib.suppress(OSError):
                conn.setsockopt(socket.SOL_SOCKET, option, SOCKET_BUFFER)
        if self._stopped is None or self._stopped.is_set():
            conn.close()  # not serving: the client sees its connection closed
        elif self._lane is not None and self.plain:
            self._admit(self._lane, conn)
        else:
            self._connect(conn, None)

    def _admit(self, lane: FastLane, conn: socket.socket) -> None:
        """A new client on the fast lane, unless max_sessions are open."""
        if self.full():
            self.refused += 1
            conn.close()
            return
        try:
            lane.admit(conn)
        except OSError as exc:  # that client only (epoll out of memory, say)
            conn.close()
            self.notices.note("accept", f"cannot take a client: {_reason(exc)}")

    def forget(self, session: SimSession) -> None:
        """A session whose connection is gone: neither open nor being shed any more."""
        self.sessions.discard(session)
        self._shedding.discard(session)

    def adopt(self, session: SimSession, conn: socket.socket) -> None:
        """A transport for a session leaving the fast lane (``SimSession.hand_over``)."""
        self._connect(conn, session)

    def _connect(self, conn: socket.socket, session: SimSession | None) -> None:
        """Serve ``conn`` through an asyncio transport: ``session`` (one leaving the lane)
        or a new one."""
        loop = asyncio.get_running_loop()
        adopted = session is not None
        protocol = session or SimSession(self)
        task = loop.create_task(self._take_client(loop, conn, protocol, adopted))
        self._connecting.add(task)
        task.add_done_callback(functools.partial(self._connected, conn, protocol, adopted))

    def _connected(
        self, conn: socket.socket, session: SimSession, adopted: bool, task: asyncio.Task[None]
    ) -> None:
        """Stopped before the transport was made (perhaps before the task began): the
        connection is closed, not left to the garbage collector."""
        self._connecting.discard(task)
        if task.cancelled() and not session.connected:
            conn.close()
            if adopted:
                session.connection_lost(None)

    async def _take_client(
        self,
        loop: asyncio.AbstractEventLoop,
        conn: socket.socket,
        session: SimSession,
        adopted: bool,
    ) -> None:
        try:
            conn.setblocking(False)
            await loop.connect_accepted_socket(lambda: session, conn)
        except Exception as exc:  # that client only: the others go on being served
            conn.close()
            if adopted:
                session.connection_lost(None)
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
