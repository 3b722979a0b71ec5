"""The session driver: one blocking socket, driven by the thread that owns the session.

Connecting, the one exchange, the resend of a GET, the idle check and the abort of a
timed-out PUT share the socket's state, and live here; what is done to the socket below
the protocol (its options, asking it without blocking, resetting it, the words for a
failure) is :mod:`.sockets`, which holds no state.

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

import select
import socket
import time
from collections.abc import Callable
from typing import Any

from ..protocol import RequestLine, Variant, VarKind, format_variant
from ..protocol.request import Request, get_for, put_for, raw_request
from ..protocol.text import escape_bytes
from . import sockets
from .machine import SessionMachine, Verdict, no_reply
from .observers import Observers
from .sockets import READ_SIZE
from .types import (
    DEFAULT_PORT,
    DEFAULT_TIMEOUT,
    MAX_REPLY_LINE,
    ConnectFailed,
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

#: A Reply made straight from its fields' tuple (the named tuple's own ``__new__`` is
#: one more Python call, on every exchange).
_new_reply = tuple.__new__

_POLL = getattr(select, "poll", None)  # POSIX; select.select serves where it is missing

#: Once a peer has sent a line nobody asked for, each request first waits this long
#: (seconds) after the last reply for the socket to stay quiet; each further stray doubles
#: the wait, up to MAX_SETTLE. A well-behaved controller never pays it.
SETTLE = 0.002
MAX_SETTLE = 0.05


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
        opener: Callable[[], socket.socket] | None = None,
    ) -> None:
        """``unreachable_hint`` is added to a failure to connect (a bare name that is
        no profile: ``no profile named cel3 in FILE``). ``opener`` makes each connection
        in place of a TCP connect to ``host:port`` (the built-in simulator's socket
        pair, which listens nowhere)."""
        self.host = host
        self._opener = opener
        self.unreachable_hint = unreachable_hint
        self.port = port
        self.timeout = timeout
        self.connect_timeout = connect_timeout if connect_timeout is not None else timeout
        self.last_rtt: float | None = None
        self._machine = SessionMachine(max_line)
        self._observers = Observers()
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
        self._observers.frames.append(observer)

    def remove_frame_observer(self, observer: FrameObserver) -> None:
        self._observers.frames.remove(observer)

    def add_state_observer(self, observer: StateObserver) -> None:
        self._observers.states.append(observer)

    def add_resend_observer(self, observer: Callable[[str], None]) -> None:
        """Told why, when a GET is sent again on a fresh connection (see :meth:`exchange`)."""
        self._observers.resends.append(observer)

    def _set_state(self, state: State) -> None:
        if state != self._state:
            self._state = state
            self._observers.state(state)

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
            self._observers.resend(str(exc))
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
        observed = observe and bool(self._observers.frames)
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
                f"the connection failed while sending: {sockets.reason_of(exc)}", before_reply=True
            ) from None
        if observed:
            self._observers.publish(Frame(sent_time, "tx", data, poll=poll, request=request.line))
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
        sockets.set_timeout(sock, remaining, self._kernel_timeout)
        try:
            return sock.recv(READ_SIZE)
        except OSError as exc:
            raise self._read_failed(exc) from None
        finally:
            if self._sock is sock:
                sockets.set_timeout(sock, self.timeout, self._kernel_timeout)

    def _read_failed(self, exc: OSError) -> TransportError:
        """What a failed read means: no reply in time (BlockingIOError: SO_RCVTIMEO ran
        out), the peer closed it (a reset), or the connection failed."""
        if isinstance(exc, TimeoutError | BlockingIOError):
            return self._timed_out()
        if isinstance(exc, ConnectionError):
            return self._lost()
        return self._lost(f"the connection failed: {sockets.reason_of(exc)}")

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
        self._observers.read(verdict, arrived, rtt, poll, asked, observers)
        if verdict.strays:
            self._saw_stray()
        if verdict.drop:
            self._drop()
        if verdict.problem is not None or answer is None or response is None:
            raise no_reply(verdict)
        self._replied_at = now
        self.last_rtt = rtt
        return Reply(answer, response, rtt)

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
            self._observers.cut_short(fragment, in_flight.line if in_flight is not None else None)
        self._drop(abort=True)  # nothing more of ours may reach a peer that dropped us
        detail = f" after '{escape_bytes(fragment)}'" if fragment else ""
        return Disconnected(f"{message}{detail}", fragment or None, before_reply=not fragment)

    # ---------------------------------------------------------- stray bytes

    def has_unread(self, timeout: float = 0.0) -> bool:
        """True when bytes, EOF or an error wait unread on the open connection, after
        waiting up to ``timeout`` seconds for them (a diagnostic: tests use it to know a
        stray line has landed before the next request)."""
        sock = self._sock
        return sock is not None and sockets.readable(sock, timeout)

    def _peer_spoke(self, sock: socket.socket) -> bool:
        """True when bytes, EOF or an error wait on the connection: one syscall, no wait."""
        return self._machine.holds_stray() or sockets.readable(sock, 0.0, self._poll)

    def _saw_stray(self) -> None:
        """A line nobody asked for: settle before each request from now on, longer each time."""
        self._settle = min(self._settle * 2, MAX_SETTLE) if self._settle else SETTLE

    def _discard_waiting(self, sock: socket.socket) -> Verdict | None:
        """Log what waits as unsolicited and drop the connection: what waited (strays
        empty: the peer closed it, with nothing said); None when it was only the LF of a
        CRLF peer's last reply, consumed here, and the connection is kept."""
        data, still_open = sockets.read_waiting(sock)
        verdict = self._machine.waiting_verdict(data, still_open)
        if not verdict.drop:
            return None
        if verdict.strays:
            self._saw_stray()
        self._observers.strays(verdict.strays)
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
            sock = (
                self._opener()
                if self._opener is not None
                else socket.create_connection((self.host, self.port), self.connect_timeout)
            )
        except (OSError, UnicodeError, ValueError) as exc:  # TimeoutError is an OSError
            self._set_state("closed")
            hint = f" ({self.unreachable_hint})" if self.unreachable_hint else ""
            why, problem = sockets.reason_of(exc), sockets.problem_of(exc)
            raise ConnectFailed(
                f"cannot connect to {self.address}: {why}{hint}", problem=problem
            ) from None
        self._kernel_timeout = sockets.prepare(sock, self.timeout)
        self._sock = sock
        self._machine.reset()
        if _POLL is not None:
            self._poll = _POLL()
            self._poll.register(sock, select.POLLIN)
        if self._peer_spoke(sock) and sockets.ended(sock) is not None:
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
            sockets.close(sock, abort)
        self._set_state("closed")

    def check_idle(self) -> str | None:
        """For an idle session (the owning thread, between requests): why its open
        connection is dead (the peer closed it, keepalive gave up), which drops it; None
        while it lives or when none is open. Bytes nobody asked for are left for the
        next request's stray check."""
        sock = self._sock
        if sock is None or not self._peer_spoke(sock) or self._machine.holds_stray():
            return None
        reason = sockets.ended(sock)  # None: a stray line, which the next request logs
        if reason is not None:
            self._drop()
        return reason

    def cancel(self) -> None:
        """Cut short the request in flight from another thread (it fails with
        Disconnected, the connection is dropped); later requests connect again."""
        self._cancel_requested = True
        sock = self._sock
        if sock is not None:
            sockets.shut(sock)

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
