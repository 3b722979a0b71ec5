"""The session driver: one blocking socket, driven by the thread that owns the session.

Over 450 lines on purpose: this is the only client code that touches a socket, and
connecting, the one exchange, the resend of a GET, the idle check, keepalive and the
abort of a timed-out PUT all share the socket's state; split, they would share it
through attributes of one another.

The protocol allows one request in flight, so a request is ``sendall`` then ``recv``
until the reply: no event loop between the bytes and the caller. The rules live in
:class:`~.machine.SessionMachine`; this class only moves bytes, keeps time and tells
its observers what crossed. Not thread-safe: one thread owns a session (the engine's,
or the CLI's main thread); only :meth:`interrupt` may be called from another thread.

The protocol has no request ids, so after a timeout, a reply that cannot belong to
its request, or bytes that arrive while nothing waits, the connection is dropped and
a fresh one opened for the next request: a late reply can never be taken for the
answer to a later one. Before each request the socket is asked (one ``poll``, or
``select`` where there is none) whether anything waits unread, for the same reason.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import select
import socket
import struct
import sys
import time
from collections.abc import Callable
from typing import Any

from ..protocol import RequestLine, Variant, VarKind, format_variant
from ..protocol.request import Request, get_for, put_for, raw_request
from ..protocol.text import escape_bytes
from .machine import SessionMachine, Verdict, bad_reply_message
from .types import (
    DEFAULT_PORT,
    DEFAULT_TIMEOUT,
    MAX_REPLY_LINE,
    BadReply,
    ConnectFailed,
    ConnectProblem,
    Disconnected,
    Frame,
    FrameObserver,
    NotSent,
    Reply,
    RequestTimeout,
    State,
    StateObserver,
    TransportError,
)

logger = logging.getLogger(__name__)

#: A Reply made straight from its fields' tuple (the named tuple's own ``__new__`` is
#: one more Python call, on every exchange).
_new_reply = tuple.__new__

_POLL = getattr(select, "poll", None)  # POSIX; select.select serves where it is missing
READ_SIZE = 65536

#: Once a peer has sent a line nobody asked for, each request first waits this long
#: (seconds) after the last reply for the socket to stay quiet; each further stray doubles
#: the wait, up to MAX_SETTLE. A well-behaved controller never pays it.
SETTLE = 0.002
MAX_SETTLE = 0.05

#: TCP keepalive: an idle connection is probed after KEEPALIVE_IDLE seconds of silence,
#: every KEEPALIVE_INTERVAL seconds, and given up after KEEPALIVE_COUNT unanswered
#: probes: a controller that vanished (rebooted while the cable was out) is known dead
#: about 11 s into a quiet spell, not at the next command.
KEEPALIVE_IDLE = 5
KEEPALIVE_INTERVAL = 2
KEEPALIVE_COUNT = 3


class Session:
    """One session to a controller: ``get``, ``put``, ``send_raw`` or ``exchange``."""

    def __init__(
        self,
        host: str,
        port: int = DEFAULT_PORT,
        *,
        timeout: float = DEFAULT_TIMEOUT,
        connect_timeout: float | None = None,
        max_line: int = MAX_REPLY_LINE,
        unreachable_hint: str | None = None,
    ) -> None:
        """``unreachable_hint`` is added to a failure to connect (a bare name that is
        no profile: ``no profile named cel3 in FILE``)."""
        self.host = host
        self.unreachable_hint = unreachable_hint
        self.port = port
        self.timeout = timeout
        self.connect_timeout = connect_timeout if connect_timeout is not None else timeout
        self.last_rtt: float | None = None
        self._machine = SessionMachine(max_line)
        self._frame_observers: list[FrameObserver] = []
        self._state_observers: list[StateObserver] = []
        self._resend_observers: list[Callable[[str], None]] = []
        self._state: State = "closed"
        self._sock: socket.socket | None = None
        self._poll: Any = None
        self._replied_at = 0.0
        self._settle = 0.0  # the peer has sent lines nobody asked for: settle this long first
        self._kernel_timeout = False
        self._interrupted = False  # set by interrupt(): no new connection is opened
        self._cancel_requested = False  # set by cancel(): the request in flight was cut

    # ------------------------------------------------------------ observers

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    @property
    def state(self) -> State:
        return self._state

    def add_frame_observer(self, observer: FrameObserver) -> None:
        self._frame_observers.append(observer)

    def remove_frame_observer(self, observer: FrameObserver) -> None:
        self._frame_observers.remove(observer)

    def add_state_observer(self, observer: StateObserver) -> None:
        self._state_observers.append(observer)

    def add_resend_observer(self, observer: Callable[[str], None]) -> None:
        """Told why, when a GET is sent again on a fresh connection (see :meth:`exchange`)."""
        self._resend_observers.append(observer)

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

    def get(self, kind: VarKind, index: int, *, poll: bool = False) -> Reply:
        return self.exchange(get_for(kind, index), poll=poll)

    def put(self, kind: VarKind, index: int, value: Variant) -> Reply:
        return self.exchange(put_for(kind, index, format_variant(value)))

    def send_raw(self, text: str) -> Reply:
        return self.exchange(raw_request(text))

    def exchange(
        self,
        request: Request,
        *,
        poll: bool = False,
        cancelled: Callable[[], bool] | None = None,
        observe: bool = True,
    ) -> Reply:
        """Send one request and wait for its reply.

        ``observe`` False: no frame of this request or its reply goes to the frame
        observers (a poll nobody shows or records); lines nobody asked for always do.

        Raises a TransportError when no trustworthy reply came; the connection is then
        gone, and the next request opens a fresh one. ``cancelled`` is the job's: asked
        right before the bytes go out, and NotSent raised (nothing sent) when it says so.
        A GET whose reused connection turns out dead before any byte of its reply came
        (a controller that rebooted during a quiet spell) is sent once more on a fresh
        connection: it changes nothing. Nothing else is ever sent twice.
        """
        reused = self._sock is not None
        try:
            return self._exchange_once(request, poll, cancelled, observe)
        except Disconnected as exc:
            if not (reused and exc.before_reply and request.read_only_safe):
                raise
            if self._interrupted or self._cancel_requested:
                raise
            for observer in self._resend_observers:
                observer(str(exc))
        return self._exchange_once(request, poll, cancelled, observe)

    def _exchange_once(
        self,
        request: Request,
        poll: bool,
        cancelled: Callable[[], bool] | None,
        observe: bool = True,
    ) -> Reply:
        fresh = self._sock is None
        sock = self._sock or self._connected()
        if self._settle:
            # This peer has sent lines nobody asked for: leave it a moment after each
            # reply to finish, so a stray lands before the next request, not as its answer.
            wait = self._settle - (time.perf_counter() - self._replied_at)
            if wait > 0:
                self.has_unread(wait)
        self._cancel_requested = False
        machine = self._machine
        # The stray check (the usual case, inlined: nothing held, one poll that says no).
        quiet = self._poll is not None and not machine.pending and not self._poll.poll(0)
        if not quiet and self._peer_spoke(sock):
            dropped = self._discard_waiting(sock)
            if dropped is not None:
                if fresh and not dropped.strays:
                    # Closed as soon as it opened: no second connection in this one
                    # exchange (the caller's backoff decides when to try again).
                    raise Disconnected(
                        "the controller closed the connection as soon as it opened",
                        before_reply=True,
                    )
                sock = self._connected()
        if cancelled is not None and cancelled():
            raise NotSent("not sent: cancelled")
        data = machine.begin(request)
        # Both clocks read before sendall: after it the thread may run again only once
        # the reply is in (the GIL, the scheduler), and the frame must say when it left.
        # (The wall clock only when someone keeps frames: they alone are stamped.)
        observed = observe and bool(self._frame_observers)
        sent_at = time.perf_counter()
        sent_time = time.time() if observed else 0.0
        try:
            sock.sendall(data)
        except (TimeoutError, BlockingIOError):  # the peer has not read for a timeout
            raise self._timed_out() from None
        except ConnectionError:  # reset or broken pipe: the peer closed it
            raise self._lost() from None
        except OSError as exc:
            self._drop()
            raise Disconnected(
                f"the connection failed while sending: {_reason(exc)}", before_reply=True
            ) from None
        if observed:
            self._publish(Frame(sent_time, "tx", data, poll=poll, request=request.line))
        else:  # the usual case, inlined: the whole good reply in the first read
            try:
                chunk = sock.recv(READ_SIZE)
            except OSError as exc:
                raise self._read_failed(exc) from None
            verdict = machine.feed(chunk) if chunk else None
            if verdict is not None and verdict.usual:
                now = time.perf_counter()
                rtt = now - sent_at
                self._replied_at, self.last_rtt = now, rtt
                return _new_reply(Reply, (verdict.answer, verdict.response, rtt))
            return self._await_reply(
                sock, sent_at, sent_time, poll, request.line, observed, chunk, verdict
            )
        return self._await_reply(sock, sent_at, sent_time, poll, request.line, observed)

    def _await_reply(
        self,
        sock: socket.socket,
        sent_at: float,
        sent_time: float,
        poll: bool,
        asked: RequestLine,
        observed: bool,
        chunk: bytes | None = None,
        verdict: Verdict | None = None,
    ) -> Reply:
        """The reply to the request sent at ``sent_at`` (``time.perf_counter()``), which
        is ``sent_time`` (``time.time()``): a reply's frame is stamped ``sent_time + rtt``,
        so the log's times and gaps agree with the round trip. ``asked`` is the request's
        line, carried by the frames of its reply. ``chunk``: the first read, when the caller
        made it already (with its ``verdict``, when fed; empty: the peer closed)."""
        machine = self._machine
        if chunk is None:
            try:
                chunk = sock.recv(READ_SIZE)
            except OSError as exc:
                raise self._read_failed(exc) from None
        while True:
            now = time.perf_counter()
            if not chunk:
                raise self._lost()
            if verdict is None:
                verdict = machine.feed(chunk)
            if verdict.usual and not observed:  # the usual reply, with no frame to publish
                rtt = now - sent_at
                self._replied_at, self.last_rtt = now, rtt
                return _new_reply(Reply, (verdict.answer, verdict.response, rtt))
            if verdict.answer is None and not verdict.drop:
                chunk, verdict = self._read_more(sock, sent_at + self.timeout), None
                continue
            # A frame's time: the send's wall clock plus the round trip (read now when
            # the send had no frame: only lines nobody asked for are published then).
            arrived = sent_time + now - sent_at if sent_time else time.time()
            return self._conclude(verdict, now - sent_at, poll, now, arrived, asked, observed)

    def _read_more(self, sock: socket.socket, deadline: float) -> bytes:
        """A later read of one reply: within what is left of its timeout."""
        remaining = deadline - time.perf_counter()
        if remaining <= 0:
            raise self._timed_out()
        self._set_timeout(sock, remaining)
        try:
            return sock.recv(READ_SIZE)
        except OSError as exc:
            raise self._read_failed(exc) from None
        finally:
            if self._sock is sock:
                self._set_timeout(sock, self.timeout)

    def _read_failed(self, exc: OSError) -> TransportError:
        """What a failed read means: no reply in time (BlockingIOError: SO_RCVTIMEO ran
        out), the peer closed it (a reset), or the connection failed."""
        if isinstance(exc, TimeoutError | BlockingIOError):
            return self._timed_out()
        if isinstance(exc, ConnectionError):
            return self._lost()
        return self._lost(f"the connection failed: {_reason(exc)}")

    def _conclude(
        self,
        verdict: Verdict,
        rtt: float,
        poll: bool,
        now: float,
        arrived: float,
        asked: RequestLine,
        observers: bool,
    ) -> Reply:
        answer = verdict.answer
        response = verdict.response
        if answer is not None and observers:
            self._publish(
                Frame(
                    arrived,
                    "rx",
                    answer + b"\r",
                    rtt,
                    poll=poll,
                    response=response,
                    problem=verdict.problem,
                    request=asked,
                )
            )
        if verdict.strays:
            self._saw_stray()
        for stray in verdict.strays:
            self._publish(Frame(arrived, "rx", stray, unsolicited=True))
        if verdict.too_long is not None:
            unasked = answer is not None  # the reply came: the tail answers nothing
            self._publish(
                Frame(
                    arrived,
                    "rx",
                    verdict.too_long,
                    unsolicited=unasked,
                    request=None if unasked else asked,
                )
            )
        if verdict.drop:
            self._drop()
        if verdict.problem is not None:
            if answer is None:  # too long: the tail is in the log
                raise BadReply(verdict.problem, verdict.too_long)
            raise BadReply(bad_reply_message(answer, verdict.problem), answer)
        if answer is None or response is None:
            raise Disconnected("the connection was dropped: a line nobody asked for came")
        self._replied_at = now
        self.last_rtt = rtt
        return Reply(answer, response, rtt)

    def _set_timeout(self, sock: socket.socket, seconds: float) -> None:
        if not (self._kernel_timeout and _set_kernel_timeout(sock, seconds)):
            sock.settimeout(seconds)

    def _timed_out(self) -> RequestTimeout:
        # Aborted, not closed: a graceful close lets the kernel keep re-sending the
        # request, so a PUT held up on the network could land after its read-back.
        self._drop(abort=True)
        return RequestTimeout(f"no reply within {self.timeout:g} s")

    def _lost(self, message: str = "the controller closed the connection") -> Disconnected:
        if self._cancel_requested:
            message = "cancelled"
        fragment = self._machine.pending
        if fragment:
            in_flight = self._machine.in_flight  # the request this fragment began to answer
            asked = in_flight.line if in_flight is not None else None
            self._publish(Frame(time.time(), "rx", fragment, request=asked))
        self._drop(abort=True)  # nothing more of ours may reach a peer that dropped us
        detail = f" after '{escape_bytes(fragment)}'" if fragment else ""
        return Disconnected(f"{message}{detail}", fragment or None, before_reply=not fragment)

    # ---------------------------------------------------------- stray bytes

    def has_unread(self, timeout: float = 0.0) -> bool:
        """True when bytes, EOF or an error wait unread on the open connection, after
        waiting up to ``timeout`` seconds for them (a diagnostic: tests use it to know a
        stray line has landed before the next request)."""
        sock = self._sock
        if sock is None:
            return False
        try:
            return bool(select.select((sock,), (), (), timeout)[0])
        except (OSError, ValueError):
            return True

    def _peer_spoke(self, sock: socket.socket) -> bool:
        """True when bytes, EOF or an error wait on the connection: one syscall, no wait."""
        if self._machine.holds_stray():
            return True
        try:
            if self._poll is not None:
                return bool(self._poll.poll(0))
            return bool(select.select((sock,), (), (), 0)[0])
        except (OSError, ValueError):
            return True  # a socket that cannot be asked cannot be trusted

    def _saw_stray(self) -> None:
        """A line nobody asked for: settle before each request from now on, longer each time."""
        self._settle = min(self._settle * 2, MAX_SETTLE) if self._settle else SETTLE

    def _discard_waiting(self, sock: socket.socket) -> Verdict | None:
        """Log what waits as unsolicited and drop the connection: what waited (strays
        empty: the peer closed it, with nothing said); None when it was only the LF of a
        CRLF peer's last reply, consumed here, and the connection is kept."""
        data, still_open = _read_waiting(sock)
        verdict = self._machine.waiting_verdict(data, still_open)
        if not verdict.drop:
            return None
        if verdict.strays:
            self._saw_stray()
        for line in verdict.strays:
            self._publish(Frame(time.time(), "rx", line, unsolicited=True))
        self._drop()
        return verdict

    # ---------------------------------------------------------- connection

    def connect(self) -> None:
        """Open the connection now rather than at the first request."""
        self._connected()

    def _connected(self) -> socket.socket:
        sock = self._sock
        if sock is not None:
            return sock
        if self._interrupted:
            raise Disconnected("the session was stopped")
        self._set_state("connecting")
        try:
            sock = socket.create_connection((self.host, self.port), self.connect_timeout)
        except (OSError, UnicodeError, ValueError) as exc:  # TimeoutError is an OSError
            self._set_state("closed")
            hint = f" ({self.unreachable_hint})" if self.unreachable_hint else ""
            raise ConnectFailed(
                f"cannot connect to {self.address}: {_reason(exc)}{hint}", problem=_problem(exc)
            ) from None
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        _set_keepalive(sock)
        self._kernel_timeout = _set_kernel_timeout(sock, self.timeout)
        sock.settimeout(None if self._kernel_timeout else self.timeout)
        self._sock = sock
        self._machine.reset()
        if _POLL is not None:
            self._poll = _POLL()
            self._poll.register(sock, select.POLLIN)
        if self._peer_spoke(sock) and _closed_at_once(sock):
            # Closed by the peer as soon as it was made: say so now rather than send into it.
            self._drop()
            raise Disconnected("the controller closed the connection as soon as it was made")
        self._set_state("connected")
        return sock

    def _drop(self, abort: bool = False) -> None:
        """Close the connection so nothing more it carries can be read; with ``abort``,
        reset it, so what it still holds unsent is discarded rather than delivered."""
        sock, self._sock, self._poll = self._sock, None, None
        self._machine.reset()
        if sock is not None:
            if abort:
                _discard_unsent(sock)
            with contextlib.suppress(OSError):
                sock.close()
        self._set_state("closed")

    def check_idle(self) -> str | None:
        """For an idle session (the owning thread, between requests): why its open
        connection is dead (the peer closed it, keepalive gave up), which drops it; None
        while it lives or when none is open. Bytes nobody asked for are left for the
        next request's stray check."""
        sock = self._sock
        if sock is None or not self._peer_spoke(sock) or self._machine.holds_stray():
            return None
        timeout = sock.gettimeout()
        try:
            sock.setblocking(False)
            try:
                if sock.recv(1, socket.MSG_PEEK):
                    return None  # a stray line: the next request logs it
                reason = "the controller closed the connection"
            finally:
                sock.settimeout(timeout)
        except BlockingIOError:
            return None
        except OSError as exc:
            reason = f"the connection failed: {_reason(exc)}"
        self._drop()
        return reason

    def cancel(self) -> None:
        """Cut short the request in flight from another thread (it fails with
        Disconnected, the connection is dropped); later requests connect again."""
        self._cancel_requested = True
        sock = self._sock
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)

    def interrupt(self) -> None:
        """Wake a request blocked on this session from another thread (it then fails
        with Disconnected) and refuse new connections from now on; the owning thread
        closes the socket."""
        self._interrupted = True
        self.cancel()

    def close(self) -> None:
        self._drop()

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def _set_kernel_timeout(sock: socket.socket, seconds: float) -> bool:
    """Put the send and receive timeouts in the kernel (SO_SNDTIMEO, SO_RCVTIMEO), so a
    blocking ``recv`` is one system call instead of Python's poll-then-recv. False where
    the options cannot be set: the caller then uses Python's socket timeout."""
    try:
        if sys.platform == "win32":
            value = struct.pack("=L", max(1, round(seconds * 1000)))  # a DWORD of ms
        else:
            whole = int(seconds)
            value = struct.pack("@ll", whole, max(1, int((seconds - whole) * 1e6)))
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, value)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDTIMEO, value)
    except (OSError, AttributeError, struct.error, OverflowError):
        return False
    return True


def _set_keepalive(sock: socket.socket) -> None:
    """TCP keepalive with an idle time of seconds (the systems' default is two hours),
    on Linux, macOS and Windows; left at the system's where an option is missing."""
    with contextlib.suppress(OSError, AttributeError, ValueError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
        if sys.platform == "win32":
            ms = (1, KEEPALIVE_IDLE * 1000, KEEPALIVE_INTERVAL * 1000)
            sock.ioctl(socket.SIO_KEEPALIVE_VALS, ms)  # type: ignore[attr-defined]
            return
        idle = getattr(socket, "TCP_KEEPIDLE", None) or getattr(socket, "TCP_KEEPALIVE", None)
        for option, value in (
            (idle, KEEPALIVE_IDLE),
            (getattr(socket, "TCP_KEEPINTVL", None), KEEPALIVE_INTERVAL),
            (getattr(socket, "TCP_KEEPCNT", None), KEEPALIVE_COUNT),
        ):
            if option is not None:
                sock.setsockopt(socket.IPPROTO_TCP, option, value)


def _discard_unsent(sock: socket.socket) -> None:
    """SO_LINGER on, time 0: the close that follows resets the connection."""
    layout = "=HH" if sys.platform == "win32" else "ii"
    with contextlib.suppress(OSError, struct.error):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack(layout, 1, 0))


def _closed_at_once(sock: socket.socket) -> bool:
    """True when a fresh connection already reads EOF or an error (peeked, not taken)."""
    timeout = sock.gettimeout()
    try:
        sock.setblocking(False)
        try:
            return sock.recv(1, socket.MSG_PEEK) == b""
        finally:
            sock.settimeout(timeout)
    except BlockingIOError:
        return False
    except OSError:
        return True


def _read_waiting(sock: socket.socket) -> tuple[bytes, bool]:
    """What waits on ``sock``, read without blocking for the log, and whether the
    connection is still open (the read stopped for want of bytes, not at EOF or error)."""
    chunks: list[bytes] = []
    limit = MAX_REPLY_LINE
    still_open = False
    timeout = sock.gettimeout()
    try:
        sock.setblocking(False)
        size = 0
        while size < limit:
            chunk = sock.recv(min(READ_SIZE, limit - size))
            if not chunk:
                break  # EOF
            chunks.append(chunk)
            size += len(chunk)
    except BlockingIOError:
        still_open = True  # all read
    except OSError:
        pass  # reset: drop it all the same
    finally:
        with contextlib.suppress(OSError):
            sock.settimeout(timeout)
    return b"".join(chunks), still_open


#: errno values (POSIX and WinSock) of a host or network that cannot be reached.
_UNREACHABLE = {
    getattr(errno, "EHOSTUNREACH", 113),
    getattr(errno, "ENETUNREACH", 101),
    getattr(errno, "EHOSTDOWN", 112),
    getattr(errno, "ENETDOWN", 100),
    10065,  # WSAEHOSTUNREACH
    10051,  # WSAENETUNREACH
    10064,  # WSAEHOSTDOWN
    10050,  # WSAENETDOWN
}


def _problem(exc: BaseException) -> ConnectProblem:
    """Why a connection could not be opened, in a word, the same on every system."""
    if isinstance(exc, socket.gaierror | UnicodeError | ValueError):
        return "unknown host"
    if isinstance(exc, ConnectionRefusedError):
        return "refused"
    if isinstance(exc, TimeoutError):
        return "timed out"
    if isinstance(exc, OSError) and (
        exc.errno in _UNREACHABLE or getattr(exc, "winerror", None) in _UNREACHABLE
    ):
        return "unreachable"
    return "failed"


#: The words for the failures a user can act on, keyed by errno and WinSock code, so
#: Linux, macOS and Windows say them alike: os.strerror knows no WinSock code (it says
#: "Unknown error" for 10061), and each system words its own codes its own way.
_WORDS = {
    errno.ECONNREFUSED: "Connection refused",
    10061: "Connection refused",  # WSAECONNREFUSED
    errno.ETIMEDOUT: "timed out",
    10060: "timed out",  # WSAETIMEDOUT
    errno.EHOSTUNREACH: "No route to host",
    10065: "No route to host",  # WSAEHOSTUNREACH
    errno.ENETUNREACH: "Network is unreachable",
    10051: "Network is unreachable",  # WSAENETUNREACH
}

#: getaddrinfo's codes for a name that does not exist: glibc and macOS (EAI_NONAME,
#: EAI_NODATA) and WinSock (WSAHOST_NOT_FOUND 11001, WSANO_DATA 11004). They are a
#: table of their own: macOS's EAI_NONAME is 8, an errno too.
_NAME_NOT_FOUND = {
    socket.EAI_NONAME,
    getattr(socket, "EAI_NODATA", socket.EAI_NONAME),
    11001,  # WSAHOST_NOT_FOUND
    11004,  # WSANO_DATA
}


def _reason(exc: BaseException) -> str:
    """Why a connection failed, in words: never 'Unknown error -2', nor Windows'
    'Unknown error' for a WinSock code (a table first, then the exception's own text)."""
    if isinstance(exc, TimeoutError):
        return "timed out"
    if isinstance(exc, socket.gaierror):
        if exc.errno in _NAME_NOT_FOUND:
            return "host not found"
        if exc.strerror:
            return exc.strerror  # "Temporary failure in name resolution"
    elif isinstance(exc, OSError):
        for code in (getattr(exc, "winerror", None), exc.errno):
            if code in _WORDS:
                return _WORDS[code]
        if exc.strerror:
            return exc.strerror  # the system's own words for this exception
        if exc.errno and exc.errno > 0:
            return os.strerror(exc.errno)
    if isinstance(exc, UnicodeError | ValueError):
        return "not a valid host name"
    return str(exc) or type(exc).__name__
