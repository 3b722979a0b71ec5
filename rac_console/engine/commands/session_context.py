"""A job's context over a plain session, for the CLI: ``run FILE`` and the one-shot
commands run through the same registry and job runner as the console, with no watch
list, no one to ask (a ``confirm`` target's write needs ``--yes``) and no poller."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from ...commands.language import VarRef
from ...commands.outcome import Outcome
from ...commands.target import Target
from ...protocol import Variant
from ...session import ConnectFailed, Session, TransportError
from ..exchange.writes import Confirm

if TYPE_CHECKING:
    from .context import CommandContext


class SessionContext:
    """A :class:`~.context.JobContext` that nobody cancels but Ctrl-C."""

    def __init__(self, session: Session, rules: Target, verify: bool = True) -> None:
        self.session: Session | None = session
        self.rules = rules
        self.verify = verify
        self.confirm: Confirm | None = None

    def cancelled(self) -> bool:
        return False

    def between(self, until: float, deadline: float) -> None:
        time.sleep(max(0.0, until - time.perf_counter()))

    def known_before(self, var: VarRef) -> Variant | None:
        return None

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
