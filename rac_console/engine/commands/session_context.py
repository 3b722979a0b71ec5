"""A job's context over a plain session, for the CLI: ``run FILE`` and the one-shot
commands run through the same registry and job runner as the console, with no watch
list, no one to ask (a ``confirm`` target's write needs ``--yes``) and no poller."""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Self

from ...commands.language import VarRef
from ...commands.outcome import Outcome
from ...commands.routing import WriteTrait
from ...commands.target import Target
from ...session import ConnectFailed, Session, TransportError
from ..exchange.conditions import sleep_until
from ..exchange.controller import Controller
from ..exchange.gate import WriteGate

if TYPE_CHECKING:
    from .context import CommandContext


class SessionContext:
    """A :class:`~.context.JobContext` that nobody cancels but Ctrl-C."""

    def __init__(self, session: Session, rules: Target, verify: bool = True) -> None:
        self._session: Session | None = session
        self.rules = rules
        self._verify = verify
        #: The command whose job this is, and what it declares (see :meth:`declaring`).
        self._declared: tuple[str, WriteTrait] = ("", WriteTrait.NEVER)

    @property
    def controller(self) -> Controller | None:
        if self._session is None:
            return None
        name, writes = self._declared
        rules = self.rules
        gate = WriteGate(rules.policy, writes, name, rules.read_only, self._verify)
        return Controller(self._session, gate)

    def declaring(self, name: str, writes: WriteTrait) -> Self:
        declared = copy.copy(self)
        declared._declared = (name, writes)
        return declared

    def cancelled(self) -> bool:
        return False

    def between(self, until: float, deadline: float) -> None:
        sleep_until(until, deadline)

    def read_back(self, outcome: Outcome) -> None:
        """Nothing watched to update."""

    def see(self, variables: tuple[VarRef, ...] | list[VarRef]) -> None:
        """No completion to offer them to."""

    def connect_failed(self, error: ConnectFailed | None) -> None:
        """The outcome says it; no status line."""

    def mark_failure(self, error: TransportError) -> None:
        """The outcome says it; no frame log."""

    def engine_context(self) -> CommandContext | None:
        """No engine: a command that needs one does not run here."""
        return None
