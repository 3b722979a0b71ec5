"""One connection to a controller, shared by the agent's engines (one per client).

Each engine gets a :class:`SharedSession`, a :class:`Session` to its code: requests go
out one at a time in the order they asked (a queue of turns), on the one connection.
A poll is answered without a request when the controller was read for it since the
engine's previous answer to that poll: the union of what the clients watch is read
once per cycle, each variable as often as the fastest client asks, and no engine ever
gets an answer older than the one it had. A typed ``get`` always goes out.

Every frame goes to the engine that asked, and to the others tagged with who asked
(``Frame.source``), through their ``foreign`` sink (thread-safe: it runs on the asking
engine's thread). A poll's frames go to another engine only while it shows its own.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from ..protocol import Request
from .blocking import Session
from .types import Frame, NotSent, Reply, State

ForeignSink = Callable[[Frame], None]
#: How often a write waiting for an earlier one looks whether its job was cancelled.
CANCEL_CHECK = 0.1


class Turns:
    """A queue of turns: whoever asked first goes first (a lock is not fair)."""

    def __init__(self) -> None:
        self._changed = threading.Condition(threading.Lock())
        self._next = 0
        self._serving = 0

    def take(self) -> None:
        """Wait for this caller's turn (then :meth:`give_up` when done)."""
        with self._changed:
            ticket = self._next
            self._next += 1
            while self._serving != ticket:
                self._changed.wait()

    def give_up(self) -> None:
        with self._changed:
            self._serving += 1
            if self._next != self._serving:  # someone waits
                self._changed.notify_all()

    @contextmanager
    def turn(self) -> Iterator[None]:
        self.take()
        try:
            yield
        finally:
            self.give_up()


#: Said to a client whose write waits for another client's earlier one.
WAITING = (
    "this write waits for {client}'s earlier write to finish: the agent sends writes in "
    "the order it received them (Esc cancels this one; nothing was sent)"
)


class FrameBudget:
    """At most ``per_second`` poll frames a second for one client's screen (a console
    shown its poll frames): a poll over it builds no frame for that client, counted
    (:meth:`take_left_out`) so that the client is told. Frames nobody builds cost the
    agent nothing: at 200 rows flat out, building and sending 40,000 a second that the
    client would drop cost a fifth of the agent's polling."""

    def __init__(self, per_second: int) -> None:
        self.rate = float(per_second)
        self._allowance = self.rate
        self._at = time.monotonic()
        self._left_out = 0
        self._lock = threading.Lock()

    def allow(self, frames: int) -> bool:
        with self._lock:
            now = time.monotonic()
            self._allowance = min(self.rate, self._allowance + (now - self._at) * self.rate)
            self._at = now
            if self._allowance >= frames:
                self._allowance -= frames
                return True
            self._left_out += frames
            return False

    def take_left_out(self) -> int:
        """The frames left out since the last call."""
        with self._lock:
            left, self._left_out = self._left_out, 0
            return left


class WriteOrder:
    """Writes in the order the agent received them, whichever client sent them: a line
    that may write takes a ticket as it arrives (:meth:`take`), and its request that
    writes waits until every line that may write and came before it has finished
    (:meth:`done`). Reads never wait. A client's lines run in its order, so the line it
    is running is its oldest ticket not done."""

    def __init__(self) -> None:
        self._changed = threading.Condition()
        self._next = 0
        self._open: dict[int, str] = {}  # ticket -> the client that holds it
        self.waiting = 0  # writes waiting now for an earlier one (agent status says it)

    def take(self, client: str) -> int:
        with self._changed:
            ticket = self._next
            self._next += 1
            self._open[ticket] = client
            return ticket

    def done(self, ticket: int) -> None:
        with self._changed:
            if self._open.pop(ticket, None) is not None:
                self._changed.notify_all()

    def done_all(self, client: str) -> None:
        """A client went away: its lines will never run."""
        with self._changed:
            for ticket in [t for t, c in self._open.items() if c == client]:
                del self._open[ticket]
            self._changed.notify_all()

    def wait_turn(
        self,
        client: str,
        cancelled: Callable[[], bool] | None = None,
        told: Callable[[str], None] | None = None,
    ) -> None:
        """Before a write of ``client``: until the lines that arrived before its own
        (its oldest ticket) have finished; NotSent if its job is cancelled meanwhile
        (Esc, Ctrl-C: nothing was sent). ``told`` hears, once, whose write it waits for."""
        with self._changed:
            mine = [t for t, c in self._open.items() if c == client]
            if not mine:
                return
            first = min(mine)
            ahead = [self._open[t] for t in sorted(self._open) if t < first]
            if ahead and told is not None:
                told(WAITING.format(client=ahead[0]))
            self.waiting += 1
            try:
                while any(t < first for t in self._open):
                    if cancelled is not None and cancelled():
                        raise NotSent("cancelled while an earlier write went first")
                    self._changed.wait(CANCEL_CHECK)
            finally:
                self.waiting -= 1


class SharedConnection:
    """The agent's one session to one controller; :meth:`attach` gives an engine its
    :class:`SharedSession`."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.turns = Turns()
        self.order = WriteOrder()
        #: The attached sessions, replaced whole on a change (read without a lock).
        self._sessions: tuple[SharedSession, ...] = ()
        self._lock = threading.Lock()
        self._asking: SharedSession | None = None  # whose request is on the wire
        #: The last good answer to each GET (its bytes): when it came, and the reply.
        self._read: dict[bytes, tuple[float, Reply]] = {}
        self.requests = 0  # requests sent
        self.shared_polls = 0  # polls answered by a read made for another
        #: The agent's own frame log (``--record``, ``--log``): every frame, tagged.
        self.record: Callable[[Frame], None] | None = None
        session.add_frame_observer(self._frame)
        session.add_state_observer(self._state)
        session.add_resend_observer(self._resend)

    @property
    def host(self) -> str:
        return self.session.host

    @property
    def port(self) -> int:
        return self.session.port

    def attach(
        self,
        source: str,
        foreign: ForeignSink,
        timeout: float,
        told: Callable[[str], None] | None = None,
        budget: FrameBudget | None = None,
    ) -> SharedSession:
        """A session for the engine of client ``source``; ``foreign`` takes the frames
        of the other clients' requests, ``told`` what the client is to be told at once
        (a write that waits for another client's), ``budget`` bounds its poll frames."""
        shared = SharedSession(self, source, foreign, timeout, told, budget)
        with self._lock:
            self._sessions = (*self._sessions, shared)
        return shared

    def detach(self, shared: SharedSession) -> None:
        with self._lock:
            self._sessions = tuple(s for s in self._sessions if s is not shared)

    @property
    def clients(self) -> int:
        return len(self._sessions)

    def close(self) -> None:
        """The agent stops: the connection closes; a request waiting its turn fails."""
        self.session.interrupt()
        with self.turns.turn():
            self.session.close()

    # ------------------------------------------------------------ on the asker's thread

    def exchange(
        self,
        asker: SharedSession,
        request: Request,
        poll: bool,
        cancelled: Callable[[], bool] | None,
        observe: bool,
    ) -> Reply:
        if poll:
            asker.shows_polls = observe
        elif request.write:
            self.order.wait_turn(asker.source, cancelled, asker.told)
        key = request.data
        turns = self.turns
        turns.take()
        try:
            if cancelled is not None and cancelled():
                raise NotSent("cancelled before it was sent")
            if poll:
                read = self._read.get(key)
                if read is not None and read[0] > asker.answered.get(key, -1.0):
                    self.shared_polls += 1
                    asker.answered[key] = read[0]
                    return read[1]
            if poll and observe and not asker.poll_frames_allowed():
                observe = asker.shows_polls = False  # over its budget: no frame built
            observed = (
                observe
                or self.record is not None
                or any(s is not asker and (not poll or s.shows_polls) for s in self._sessions)
            )
            self._asking = asker
            self.session.timeout = asker.timeout
            if not request.line.is_get:  # it may change any variable, answered or not:
                self._read.clear()  # no poll is answered from a read made before it
            try:
                self.requests += 1
                reply = self.session.exchange(
                    request, poll=poll, cancelled=cancelled, observe=observed
                )
            finally:
                self._asking = None
            if request.line.is_get:
                now = time.monotonic()
                self._read[key] = (now, reply)
                asker.answered[key] = now

            asker.last_rtt = reply.rtt
            if asker.known_state != self.session.state:
                self._tell_state(asker)
            return reply
        finally:
            turns.give_up()

    def check_idle(self, asker: SharedSession) -> str | None:
        with self.turns.turn():
            self._asking = asker
            try:
                return self.session.check_idle()
            finally:
                self._asking = None

    def connect(self, asker: SharedSession) -> None:
        with self.turns.turn():
            self._asking = asker
            try:
                self.session.connect()
            finally:
                self._asking = None
            self._tell_state(asker)

    def _tell_state(self, asker: SharedSession) -> None:
        """An engine attached to a connection opened before it hears its state: its
        status line must not say "not connected yet" while the connection serves it."""
        state = self.session.state
        if asker.known_state != state:
            asker.state_changed(state)

    # ------------------------------------------------------------ the real session's observers

    def _frame(self, frame: Frame) -> None:
        asker = self._asking
        for_all = frame.unsolicited or not frame.poll  # a poll's only where polls show
        if asker is not None and (for_all or asker.shows_polls):
            asker.frame(frame)
        tagged: Frame | None = None  # made once, and only when another takes it
        record = self.record
        if record is not None:
            tagged = self._tagged(frame, asker)
            record(tagged)
        for shared in self._attached():
            if shared is not asker and (for_all or shared.shows_polls):
                if tagged is None:
                    tagged = self._tagged(frame, asker)
                shared.foreign(tagged)

    @staticmethod
    def _tagged(frame: Frame, asker: SharedSession | None) -> Frame:
        """``frame`` naming the client that asked (a line nobody asked for names none)."""
        if asker is None or frame.unsolicited:
            return frame
        return dataclasses.replace(frame, source=asker.source)

    def _state(self, state: State) -> None:
        asker = self._asking
        if asker is not None:
            asker.state_changed(state)

    def _resend(self, reason: str) -> None:
        asker = self._asking
        if asker is not None:
            asker.resent(reason)

    def _attached(self) -> tuple[SharedSession, ...]:
        return self._sessions


class SharedSession(Session):
    """What one engine of the agent holds: a session whose requests take their turn on
    the shared connection. The engine's observers hear its own requests' frames and the
    state changes they make; the state read is the connection's own."""

    def __init__(
        self,
        connection: SharedConnection,
        source: str,
        foreign: ForeignSink,
        timeout: float,
        told: Callable[[str], None] | None = None,
        budget: FrameBudget | None = None,
    ) -> None:
        real = connection.session
        super().__init__(real.host, real.port, timeout=timeout)
        self.connection = connection
        self.source = source
        self.foreign = foreign
        self.told = told
        self.budget = budget
        self.shows_polls = True
        #: When this engine last had an answer to each GET it polls.
        self.answered: dict[bytes, float] = {}
        self._cancelled = False
        self.known_state: State = "closed"  # as this engine last heard it

    @property
    def state(self) -> State:
        return self.connection.session.state

    def poll_frames_allowed(self) -> bool:
        """Whether this poll's frames may be built for this client (its budget)."""
        return self.budget is None or self.budget.allow(2)

    def frame(self, frame: Frame) -> None:
        self._observers.publish(frame)

    def state_changed(self, state: State) -> None:
        self.known_state = state
        self._observers.state(state)

    def resent(self, reason: str) -> None:
        self._observers.resend(reason)

    def exchange(
        self,
        request: Request,
        *,
        poll: bool = False,
        cancelled: Callable[[], bool] | None = None,
        observe: bool = True,
    ) -> Reply:
        if self._cancelled:
            raise NotSent("this client's session is closed")
        return self.connection.exchange(self, request, poll, cancelled, observe)

    def connect(self) -> None:
        self.connection.connect(self)

    def check_idle(self) -> str | None:
        return self.connection.check_idle(self)

    def has_unread(self, timeout: float = 0.0) -> bool:
        return False

    def cancel(self) -> None:
        """Cut this engine's request short: when it is on the wire the connection
        goes (the others' next requests open it again), as with a session of its own."""
        if self.connection._asking is self:
            self.connection.session.cancel()

    def interrupt(self) -> None:
        self._cancelled = True
        self.cancel()

    def close(self) -> None:
        """This engine is done with the connection (it stays open for the others)."""
        self.connection.detach(self)
