"""A command's controller as its handler has it: it reads, and writes only through the
job's write gate.

A handler never holds the session: its context gives it a :class:`Controller` (None
when not connected), made over the session and the job's :class:`~.gate.WriteGate`. Its
reads go by the read path, which sends a well-formed GET and nothing else; its
:meth:`Controller.exchange` takes any GET, PUT or raw line and hands a write to the gate.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...commands.language import Exchange, Get, VarRef, Wait
from .conditions import sleep_until, wait_for
from .execute import execute, measure_latency

if TYPE_CHECKING:
    from collections.abc import Callable

    from ...commands.latency import LatencySummary
    from ...commands.outcome import Outcome
    from ...session import Session
    from .gate import WriteGate


class Controller:
    """The job's target: :meth:`get`, :meth:`read`, :meth:`latency` and :meth:`wait`
    read; :meth:`exchange` sends any GET, PUT or raw line, a write through the gate."""

    __slots__ = ("_gate", "_session")

    def __init__(self, session: Session, gate: WriteGate) -> None:
        self._session = session
        self._gate = gate

    def connect(self) -> None:
        """Open the connection now (nothing is sent); ConnectFailed or Disconnected."""
        self._session.connect()

    def get(self, var: VarRef, line: str | None = None) -> Outcome:
        """One GET of ``var``."""
        return self.read(Get(var), line)

    def read(self, command: Exchange, line: str | None = None) -> Outcome:
        """A GET, or a raw line that is a well-formed GET; anything else is refused with
        nothing sent (a write goes by :meth:`exchange`)."""
        return execute(self._session, command, line=line, cancelled=self._gate.cancelled)

    def exchange(self, command: Exchange, line: str | None = None) -> Outcome:
        """Any GET, PUT or raw line: a read is sent, a write crosses the job's gate
        (refused there when the command is declared never to write)."""
        return self._gate.exchange(self._session, command, line)

    def latency(self, var: VarRef, count: int, interval: float) -> LatencySummary:
        """``count`` GETs of ``var`` timed (see :func:`.execute.measure_latency`);
        ConnectFailed when the controller cannot be reached at all."""
        return measure_latency(self._session, var, count, interval, self._gate.cancelled)

    def wait(
        self,
        wait: Wait,
        line: str | None = None,
        between: Callable[[float, float], None] = sleep_until,
    ) -> Outcome:
        """Read ``wait.var`` until its condition holds (see :func:`.conditions.wait_for`)."""
        return wait_for(
            self._session, wait, line=line, cancelled=self._gate.cancelled, between=between
        )
