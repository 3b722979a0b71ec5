"""The one session to the target, and what is known of its health.

The connection's state as the status line says it, the backoff between tries, whether
it was lost (so "reconnected" is said) and whether it dropped early. Owned by the
engine's thread; the session's observers call in on that thread too.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from ...commands.target import Target
from ...session import ConnectFailed, Disconnected, Session, State, TransportError
from ..published.events import Connection
from ..published.status import described
from .backoff import Backoff
from .publisher import Publisher

#: Makes the session to ``host:port`` with a request timeout (see :class:`Link`).
SessionMaker = Callable[[str, int, float], Session]

if TYPE_CHECKING:  # asyncio and the simulator load only when a target names no host
    from ...sim.thread import SimulatorThread


class Link:
    def __init__(
        self,
        publisher: Publisher,
        timeout: float,
        *,
        went_down: Callable[[], None],
        connecting: Callable[[], None],
        unlisted_simulator: bool = False,
        sessions: SessionMaker | None = None,
    ) -> None:
        """``went_down``: the connection is gone (figures measured on it go);
        ``connecting``: a connect starts (the status says so at once);
        ``unlisted_simulator``: the built-in simulator listens on no port, reached over
        a socket pair of this process (see :data:`..setup.where.UNLISTED_SIMULATOR`);
        ``sessions``: makes the session to a host in place of a connection of its own
        (the agent's engines share one per controller)."""
        self._unlisted = unlisted_simulator
        self._sessions = sessions
        self._publisher = publisher
        self.timeout = timeout
        self._went_down = went_down
        self._connecting = connecting
        self.session: Session | None = None
        self.simulator: SimulatorThread | None = None
        self.host: str | None = None
        self.port = 5006
        #: closed, connecting, connected, lost, dropped, or why connecting failed.
        self.connection: Connection = "closed"
        self.ever_connected = False  # on this target: "not connected yet" until it has
        self.retry_at: float | None = None  # time.monotonic() of the next try
        self.backoff = Backoff()
        self.lost = False  # "reconnected" is said when the next exchange gets through
        self.early_drop = False  # the last connection closed before it served enough
        self.opened = 0  # targets opened: a front end forgets the last one's

    @property
    def described(self) -> str:
        """The status line's target: simulator, live controller, or none."""
        if self.session is None:
            return "NOT CONNECTED"
        return described(None if self.simulator is not None else self.host, self.port)

    def open(self, target: Target) -> None:
        """A session to ``target`` (not yet connected); the simulator starts here when
        the target names no host."""
        host, port = target.host, target.port
        opener = None
        if host is None:
            from ...sim.thread import SimulatorThread

            self.simulator = SimulatorThread(listen=not self._unlisted).start()
            host, port = self.simulator.host, self.simulator.port
            opener = self.simulator.connect if self._unlisted else None
        self.host, self.port = host, port
        self.opened += 1
        self.backoff, self.early_drop, self.lost = Backoff(), False, False
        self.ever_connected = False
        session = (
            self._sessions(host, port, self.timeout)
            if self._sessions is not None and opener is None
            else Session(
                host,
                port,
                timeout=self.timeout,
                unreachable_hint=target.unreachable_hint,
                opener=opener,
            )
        )
        session.add_frame_observer(self._publisher.frame)
        session.add_state_observer(self._on_state)
        session.add_resend_observer(self._on_resend)
        self.session = session

    def close(self) -> None:
        if self.session is not None:
            self.session.close()
            self.session = None
        if self.simulator is not None:
            self.simulator.stop()
            self.simulator = None
        self.connection = "closed"
        self.retry_at = None
        self._went_down()

    def connect_at_start(self) -> None:
        """Open the connection at start, so the status line tells the truth at once."""
        if self.session is None:
            return
        try:
            self.session.connect()
        except (ConnectFailed, Disconnected) as exc:
            if isinstance(exc, ConnectFailed):
                self.connect_failed(exc)
            raise

    def connect_failed(self, error: ConnectFailed | None = None) -> None:
        """A command found the controller unreachable: no early drop of a connection
        (none was made); the status line says why (refused, unreachable, …) rather than
        a state that looks quiet and healthy."""
        self.early_drop = False
        if error is not None:
            self.connection = error.problem
            self._publisher.status_dirty = True

    def mark_failure(self, error: TransportError) -> None:
        """One line in the log for each request that got no trustworthy reply."""
        if isinstance(error, ConnectFailed):
            return  # an outage is marked once, by the poller or the command's own result
        if isinstance(error, Disconnected):
            self._publisher.note(f"{error}: the next request reconnects")
        else:
            self._publisher.note(f"{error}: session reset")

    def check_idle(self) -> None:
        """Nothing polled, nothing typed: a connection that died in the quiet is shown
        now, not at the next command."""
        reason = self.session.check_idle() if self.session is not None else None
        if reason is not None:
            self.lost = True
            self.connection = "lost"  # not "closed": that reads as a quiet, healthy target
            self._publisher.status_dirty = True
            # An alert, not a note: the REPL prints it without frames on, at once.
            self._publisher.alert(
                f"connection lost while idle: {reason}; the next command reconnects"
            )

    def begin_retry(self, state: Connection) -> None:
        """Back off before the next try; the status line counts it down."""
        self.connection = state
        self.retry_at = time.monotonic() + self.backoff.next_delay()

    def end_retry(self) -> None:
        self.retry_at = None
        self.connection = self.session.state if self.session is not None else "closed"
        self._publisher.status_dirty = True

    def _on_state(self, state: State) -> None:
        self.connection = state
        if state != "connected":
            self._publisher.outbox.waiting_since = None
            if self.session is not None:
                self.session.last_rtt = None
            self._went_down()
        if state == "closed" and self.backoff.closed():
            self.early_drop = True  # the poller waits before its next request
        if state in ("connecting", "connected"):  # closed while connecting counts too
            self.backoff.connected()
            self.retry_at = None
            if state == "connected":
                self.ever_connected = True
            if state == "connected" and self.lost:
                self.lost = False
                self._publisher.note(f"reconnected to {self.host}:{self.port}")
        self._publisher.status_dirty = True
        if state == "connecting":
            # A connect can block for a whole timeout: the line must not say "connected"
            # meanwhile, so the change is published now, not when the loop next idles.
            self._connecting()

    def _on_resend(self, reason: str) -> None:
        """A GET found its connection dead and went again on a fresh one: marked in the
        log, so the request seen twice there is explained."""
        self._publisher.note(f"{reason}: the GET was sent again on a fresh connection")
