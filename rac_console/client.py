"""Asyncio RAC session: one TCP connection, one request in flight.

The protocol has no request ids, so a reply is only ever matched to the one
request waiting for it. After a timeout, a reply that cannot belong to its
request, or bytes that arrive while nothing waits, the connection is dropped and
a fresh one is opened for the next request: a late reply can never be taken for
the answer to a later request. Before each request the socket itself is asked
whether anything is waiting (the loop may not have read it yet), for the same
reason. What arrives after a request left cannot be told from its answer.
"""

from __future__ import annotations

import asyncio
import heapq
import itertools
import logging
import os
import select
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import Any, Literal

from .protocol import (
    FrameTooLong,
    LineDecoder,
    ProtocolError,
    RacError,
    Response,
    Variant,
    VarKind,
    decode_frame,
    encode_request,
    escape_bytes,
    format_variant,
    get_request,
    parse_response,
    put_request,
)

logger = logging.getLogger(__name__)

DEFAULT_PORT = 5006
DEFAULT_TIMEOUT = 2.0
MAX_REPLY_LINE = 64 * 1024

PRIORITY_COMMAND = 0
PRIORITY_POLL = 1
_POLL = getattr(select, "poll", None)  # POSIX; select.select serves where it is missing

#: A request made this soon (seconds) after a reply first gives up the CPU once.
YIELD_WINDOW = 0.001


def _yield_cpu() -> None:
    """Let another runnable process have the CPU: ``sched_yield`` where there is one
    (POSIX), else ``sleep(0)``, which yields the rest of the time slice on Windows."""
    sched_yield = getattr(os, "sched_yield", None)
    if sched_yield is not None:
        sched_yield()
    else:
        time.sleep(0)


Direction = Literal["tx", "rx"]
State = Literal["closed", "connecting", "connected"]


class TransportError(RacError):
    """The exchange failed on the way: no trustworthy reply came."""

    def __init__(self, message: str, raw: bytes | None = None) -> None:
        super().__init__(message)
        self.raw = raw


class ConnectFailed(TransportError):
    pass


class RequestTimeout(TransportError):
    pass


class Disconnected(TransportError):
    pass


class BadReply(TransportError):
    """A reply came but cannot be parsed or cannot belong to the request."""


@dataclass(frozen=True, slots=True)
class Frame:
    """One frame that crossed the wire, for logs and recorders.

    ``data`` holds the bytes as they crossed, CR included; a fragment cut off by
    a closed connection has no CR. ``rtt`` is set on a reply to a request.
    """

    time: float
    direction: Direction
    data: bytes
    rtt: float | None = None
    unsolicited: bool = False
    poll: bool = False


@dataclass(frozen=True, slots=True)
class Reply:
    """A request and the reply that answered it."""

    request: str
    raw: bytes
    response: Response
    rtt: float

    @property
    def text(self) -> str:
        return self.raw.decode("ascii")


FrameObserver = Callable[[Frame], None]
StateObserver = Callable[[State], None]


class _Turnstile:
    """A lock granted by priority, then arrival: typed commands overtake queued polls."""

    def __init__(self) -> None:
        self._held = False
        self._waiters: list[tuple[int, int, asyncio.Future[None]]] = []
        self._arrivals = itertools.count()

    async def acquire(self, priority: int) -> None:
        if not self._held and not self._waiters:
            self._held = True
            return
        waiter: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        heapq.heappush(self._waiters, (priority, next(self._arrivals), waiter))
        try:
            await waiter
        except asyncio.CancelledError:
            if waiter.done() and not waiter.cancelled():
                self.release()
            raise

    def release(self) -> None:
        while self._waiters:
            _, _, waiter = heapq.heappop(self._waiters)
            if not waiter.done():
                waiter.set_result(None)
                return
        self._held = False


class _SessionProtocol(asyncio.Protocol):
    def __init__(self, session: RacSession) -> None:
        self._session = session

    def data_received(self, data: bytes) -> None:
        self._session._on_data(self, data)

    def connection_lost(self, exc: Exception | None) -> None:
        self._session._on_lost(self)


class RacSession:
    """One session to a controller; ``get``, ``put`` and ``send_raw`` queue up."""

    def __init__(
        self,
        host: str,
        port: int = DEFAULT_PORT,
        *,
        timeout: float = DEFAULT_TIMEOUT,
        connect_timeout: float | None = None,
        max_line: int = MAX_REPLY_LINE,
    ) -> None:
        self.host = host
        self.port = port
        self.timeout = timeout
        self.connect_timeout = connect_timeout if connect_timeout is not None else timeout
        self.max_line = max_line
        self.last_rtt: float | None = None
        self._frame_observers: list[FrameObserver] = []
        self._state_observers: list[StateObserver] = []
        self._state: State = "closed"
        self._turn = _Turnstile()
        self._transport: asyncio.Transport | None = None
        self._protocol: _SessionProtocol | None = None
        self._decoder = LineDecoder(max_line)
        self._pending: asyncio.Future[tuple[bytes, float]] | None = None
        self._sent_at = 0.0
        self._deadline = 0.0
        self._watchdog: asyncio.TimerHandle | None = None
        self._after_cr = False
        self._polling = False
        self._replied_at = 0.0  # perf_counter() of the last reply taken
        self._sock: Any = None  # this connection's socket, asked before each request
        self._poll: Any = None
        self._fd = -1
        self._loop_reads_ahead = False

    # ------------------------------------------------------------ observers

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    @property
    def state(self) -> State:
        return self._state

    @property
    def waiting_since(self) -> float | None:
        """When (``time.perf_counter()``) the request in flight was sent; None when none is."""
        pending = self._pending
        return self._sent_at if pending is not None and not pending.done() else None

    def add_frame_observer(self, observer: FrameObserver) -> None:
        self._frame_observers.append(observer)

    def remove_frame_observer(self, observer: FrameObserver) -> None:
        self._frame_observers.remove(observer)

    def add_state_observer(self, observer: StateObserver) -> None:
        self._state_observers.append(observer)

    def _publish(self, frame: Frame) -> None:
        for observer in self._frame_observers:
            try:
                observer(frame)
            except Exception:  # an observer (a log, a recorder) must never break the session
                logger.exception("frame observer failed")

    def _set_state(self, state: State) -> None:
        if state != self._state:
            self._state = state
            for observer in self._state_observers:
                observer(state)

    # ------------------------------------------------------------ requests

    async def get(self, kind: VarKind, index: int, *, priority: int = PRIORITY_COMMAND) -> Reply:
        return await self.request(
            get_request(kind, index), check=_get_check(kind), priority=priority
        )

    async def put(self, kind: VarKind, index: int, value: Variant) -> Reply:
        return await self.request(put_request(kind, index, format_variant(value)), check=_put_check)

    async def send_raw(self, text: str) -> Reply:
        return await self.request(text)

    async def request(
        self,
        text: str,
        *,
        check: Callable[[Response], str | None] | None = None,
        priority: int = PRIORITY_COMMAND,
    ) -> Reply:
        """Send one request and wait for its reply.

        Raises InputError before sending when the text cannot be a frame, and a
        TransportError when no trustworthy reply came.
        """
        data = encode_request(text)
        await self._turn.acquire(priority)
        self._polling = priority == PRIORITY_POLL
        try:
            return await self._exchange(text, data, check)
        finally:
            self._turn.release()

    async def _exchange(
        self, text: str, data: bytes, check: Callable[[Response], str | None] | None
    ) -> Reply:
        transport = await self._connected_transport()
        if time.perf_counter() - self._replied_at < YIELD_WINDOW:
            # A peer on this machine may be one write short of a stray line: let it run
            # before asking the socket, or the stray would leave after this request.
            _yield_cpu()
        if self._loop_reads_ahead or self._peer_spoke():
            transport = await self._after_stray(transport)
        loop = asyncio.get_running_loop()
        self._sent_at = time.perf_counter()  # before _pending: waiting_since reads both
        pending = self._pending = loop.create_future()
        self._deadline = loop.time() + self.timeout
        if self._watchdog is None:
            self._watchdog = loop.call_at(self._deadline, self._check_deadline)
        try:
            self._sent_at = time.perf_counter()
            transport.write(data)
            if self._frame_observers:
                self._publish(Frame(time.time(), "tx", data, poll=self._polling))
            frame, rtt = await pending
        except BaseException:
            # Sent but no reply taken (cancelled, or failed): whatever this connection
            # carries next may be that reply, so it must not serve another request.
            if not pending.done() or pending.cancelled():
                self._drop_connection()
            raise
        finally:
            self._pending = None
        try:
            response = parse_response(decode_frame(frame))
            problem = check(response) if check else None
        except ProtocolError as exc:
            problem = str(exc)
        if problem:
            self._drop_connection()
            if len(problem) > QUOTED_BYTES:  # a parser's message may quote the reply too
                problem = problem[:QUOTED_BYTES] + "…"
            raise BadReply(f"bad reply '{_quoted(frame)}': {problem}", frame)
        self.last_rtt = rtt
        return Reply(text, frame, response, rtt)

    def _check_deadline(self) -> None:
        """One timer watches every request: rescheduled, not made anew per request."""
        self._watchdog = None
        pending = self._pending
        if pending is None or pending.done():
            return
        loop = asyncio.get_running_loop()
        if loop.time() < self._deadline:
            self._watchdog = loop.call_at(self._deadline, self._check_deadline)
            return
        pending.set_exception(RequestTimeout(f"no reply within {self.timeout:g} s"))
        self._drop_connection()

    # ---------------------------------------------------------- stray bytes

    def _peer_spoke(self) -> bool:
        """True when bytes, EOF or an error wait on the connection: one syscall, no wait.

        On every request's path, so it is kept to a poll object registered per connection.
        """
        pending = self._decoder.pending
        if pending and pending != b"\n":  # an LF is the rest of a CRLF reply: harmless
            return True
        try:
            if self._poll is not None:
                return bool(self._poll.poll(0))
            if self._fd >= 0:
                return bool(select.select((self._fd,), (), (), 0)[0])
        except (OSError, ValueError):
            return True  # a socket that cannot be asked cannot be trusted
        return False

    async def _after_stray(self, transport: asyncio.Transport) -> asyncio.Transport:
        """The connection to send on once what the peer sent unasked is dealt with.

        A line waiting when a request goes out would be read as its answer (no request
        ids), so what waits (a stray line, a late duplicate, EOF, a reset) is logged as
        unsolicited and the connection replaced. At most once per request: the fresh
        connection is not asked again.
        """
        if self._loop_reads_ahead:
            # The loop, not the socket, holds what arrived (Windows' proactor keeps a read
            # posted): two turns let it hand that to _on_data, which drops the connection.
            await asyncio.sleep(0)
            await asyncio.sleep(0)
            if self._transport is not transport:
                return await self._connected_transport()
            if not self._peer_spoke():
                return transport
        if self._discard_waiting():
            return await self._connected_transport()
        return transport

    def _discard_waiting(self) -> bool:
        """Log what waits as unsolicited and drop the connection; False when it was only
        the LF of a CRLF peer's last reply, consumed here, and the connection is kept."""
        data, still_open = _read_waiting(self._sock, self.max_line)
        waiting = self._decoder.pending + data
        if waiting == b"\n" and still_open:
            self._after_cr = False
            return False
        for line in _as_lines(waiting):
            self._publish(Frame(time.time(), "rx", line, unsolicited=True))
        self._drop_connection()
        return True

    # ---------------------------------------------------------- connection

    async def connect(self) -> None:
        """Open the connection now rather than at the first request."""
        await self._turn.acquire(PRIORITY_COMMAND)
        try:
            await self._connected_transport()
        finally:
            self._turn.release()

    async def _connected_transport(self) -> asyncio.Transport:
        if self._transport is not None and not self._transport.is_closing():
            return self._transport
        self._set_state("connecting")
        loop = asyncio.get_running_loop()
        try:
            transport, protocol = await asyncio.wait_for(
                loop.create_connection(lambda: _SessionProtocol(self), self.host, self.port),
                self.connect_timeout,
            )
        except (OSError, UnicodeError, ValueError) as exc:  # TimeoutError is an OSError
            self._set_state("closed")
            raise ConnectFailed(f"cannot connect to {self.address}: {_reason(exc)}") from None
        if transport.is_closing():
            # Closed by the peer before we got hold of it: its connection_lost has come
            # and gone, so say it now rather than send into it and wait for a timeout.
            self._set_state("closed")
            raise Disconnected("the controller closed the connection as soon as it was made")
        self._transport = transport  # type: ignore[assignment]
        self._protocol = protocol
        self._decoder.clear()
        self._after_cr = False
        self._watch_socket(transport, loop)
        self._set_state("connected")
        return self._transport  # type: ignore[return-value]

    def _watch_socket(self, transport: asyncio.BaseTransport, loop: Any) -> None:
        """Set up the per-request check of this connection's socket (a poll object is
        registered once: asking it then costs one syscall)."""
        self._sock = sock = _pollable_socket(transport, loop)
        self._loop_reads_ahead = sock is None
        self._poll, self._fd = None, -1
        if sock is None:
            return
        try:
            self._fd = sock.fileno()
            if _POLL is not None:
                self._poll = _POLL()
                self._poll.register(self._fd, select.POLLIN)
        except (OSError, ValueError):
            self._sock, self._poll, self._fd, self._loop_reads_ahead = None, None, -1, True

    def _forget_socket(self) -> None:
        self._sock, self._poll, self._fd = None, None, -1

    def _drop_connection(self) -> None:
        """Abort the connection so nothing more it carries can be read."""
        pending = self._pending
        if pending is not None and not pending.done():
            pending.set_exception(Disconnected("the session was closed"))
        if self._watchdog is not None:
            self._watchdog.cancel()
            self._watchdog = None
        if self._transport is not None:
            self._transport.abort()
            self._transport = None
            self._protocol = None
        self._forget_socket()
        self._decoder.clear()
        self._set_state("closed")

    async def close(self) -> None:
        self._drop_connection()

    async def __aenter__(self) -> RacSession:
        return self

    async def __aexit__(self, *exc_info: object) -> None:
        await self.close()

    # ----------------------------------------------------- protocol events

    def _on_data(self, protocol: _SessionProtocol, data: bytes) -> None:
        if protocol is not self._protocol:
            return  # a connection already given up on
        now = time.perf_counter()
        if data == b"\n" and self._after_cr:
            return
        self._after_cr = data.endswith(b"\r")
        pending = self._pending
        overflow: FrameTooLong | None = None
        try:
            frames = self._decoder.feed(data)
        except FrameTooLong as exc:
            frames, overflow = exc.lines, exc
        waiting = pending is not None and not pending.done()
        for frame in frames:
            if waiting:
                rtt = now - self._sent_at
                if self._frame_observers:
                    self._publish(Frame(time.time(), "rx", frame + b"\r", rtt, poll=self._polling))
                pending.set_result((frame, rtt))  # type: ignore[union-attr]
                self._replied_at = now
                waiting = False
            else:
                self._publish(Frame(time.time(), "rx", frame + b"\r", unsolicited=True))
                self._drop_connection()
        if overflow is not None:
            self._publish(Frame(time.time(), "rx", data[-256:], unsolicited=not waiting))
            if waiting:
                pending.set_exception(  # type: ignore[union-attr]
                    BadReply(f"reply too long: {overflow}", data[-256:])
                )
            self._drop_connection()
            return
        if not waiting and self._decoder.pending not in (b"", b"\n") and self._transport:
            # Bytes of a line nobody asked for: never let them prefix the next reply.
            self._publish(Frame(time.time(), "rx", self._decoder.pending, unsolicited=True))
            self._drop_connection()

    def _on_lost(self, protocol: _SessionProtocol) -> None:
        if protocol is not self._protocol:
            return
        fragment = self._decoder.pending
        pending = self._pending
        self._transport = None
        self._protocol = None
        self._forget_socket()
        self._decoder.clear()
        self._set_state("closed")
        if fragment:
            self._publish(Frame(time.time(), "rx", fragment))
        if pending is not None and not pending.done():
            detail = f" after '{escape_bytes(fragment)}'" if fragment else ""
            pending.set_exception(
                Disconnected(f"the controller closed the connection{detail}", fragment or None)
            )


def _pollable_socket(transport: asyncio.BaseTransport, loop: Any) -> Any:
    """The transport's socket when asking it tells what the loop has not read yet.

    Selector loops and uvloop read only when they poll, so anything unread is still in
    the kernel. A proactor loop (Windows' default) keeps a read posted that takes bytes
    out of the socket as they come: there the socket shows nothing, so None.
    """
    proactor = getattr(asyncio, "ProactorEventLoop", None)  # only on Windows
    if proactor is not None and isinstance(loop, proactor):
        return None
    return transport.get_extra_info("socket")


def _read_waiting(sock: Any, limit: int) -> tuple[bytes, bool]:
    """What waits on ``sock``, read without blocking for the log, and whether the
    connection is still open (the read stopped for want of bytes, not at EOF or error).

    It goes through a duplicate, as asyncio's transport socket cannot be read from;
    the connection is dropped (unless it held only an LF) right after.
    """
    chunks: list[bytes] = []
    still_open = False
    if sock is None:
        return b"", still_open
    try:
        with socket.fromfd(sock.fileno(), sock.family, sock.type) as dup:
            dup.setblocking(False)
            size = 0
            while size < limit:
                chunk = dup.recv(min(65536, limit - size))
                if not chunk:
                    break  # EOF
                chunks.append(chunk)
                size += len(chunk)
    except BlockingIOError:
        still_open = True  # all read
    except (OSError, ValueError, AttributeError):
        pass  # reset, or no way to duplicate the socket here: drop it all the same
    return b"".join(chunks), still_open


def _as_lines(data: bytes) -> list[bytes]:
    r"""``a\rb\rc`` -> ``[a\r, b\r, c]``: waiting bytes as frames, as the log shows lines."""
    *lines, rest = data.split(b"\r")
    frames = [line[1:] + b"\r" if line[:1] == b"\n" else line + b"\r" for line in lines]
    if rest and rest != b"\n":
        frames.append(rest)
    return frames


@cache
def _get_check(kind: VarKind) -> Callable[[Response], str | None]:
    """One check per variable type, made once (this is on every poll's path)."""

    def check(response: Response) -> str | None:
        if not response.ok:
            return None
        if response.variant is None:
            return "S_OK with no value"
        return kind.reply_problem(response.variant)

    return check


def _put_check(response: Response) -> str | None:
    if response.variant is not None:
        return "a PUT reply carries no value"
    return None


#: Bytes of a bad reply quoted in a message; the whole reply is in the log and --record.
QUOTED_BYTES = 120


def _quoted(frame: bytes) -> str:
    """A reply as a message quotes it: escaped, and cut when long (a 64 KiB line of
    garbage must not fill a screen)."""
    if len(frame) <= QUOTED_BYTES:
        return escape_bytes(frame)
    return f"{escape_bytes(frame[:QUOTED_BYTES])}… ({len(frame)} bytes)"


def _reason(exc: BaseException) -> str:
    """Why a connection failed, in words: never 'Unknown error -2'."""
    if isinstance(exc, TimeoutError):
        return "timed out"
    if isinstance(exc, OSError):
        if exc.errno and exc.errno > 0:
            return os.strerror(exc.errno)  # asyncio's strerror repeats the address
        if exc.strerror:
            return exc.strerror  # getaddrinfo: "Name or service not known"
    if isinstance(exc, UnicodeError | ValueError):
        return "not a valid host name"
    return str(exc) or type(exc).__name__
