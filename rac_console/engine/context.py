"""What a command's handler may use: its job, the target's rules, and (at a terminal)
the engine's parts. Handlers never see the engine itself.

:class:`JobContext` is enough for the commands that also run in ``rac-console run``
(an exchange, a wait): the CLI provides one over its own session. :class:`CommandContext`
is the engine's, for every command.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from ..commands.language import Put, Raw, VarRef
from ..commands.outcome import Outcome
from ..commands.policy import WritePolicy
from ..commands.target import Target
from ..protocol import Variant
from ..session import ConnectFailed, Session, TransportError
from .events import OK, ConfirmWrite
from .job import Job
from .writes import Confirm, plain_value

if TYPE_CHECKING:  # the engine's parts, named here; a one-shot command loads none of them
    from .csvsink import CsvSink
    from .frame_files import FrameFiles
    from .link import Link
    from .plant_tap import PlantTap
    from .poller import Poller
    from .publisher import Publisher
    from .registry import Registry


class JobContext(Protocol):
    """What an exchange or a wait needs, wherever it runs."""

    @property
    def session(self) -> Session | None: ...
    @property
    def rules(self) -> Target: ...
    @property
    def verify(self) -> bool: ...
    @property
    def confirm(self) -> Confirm | None: ...

    def cancelled(self) -> bool: ...
    def between(self, until: float, deadline: float) -> None: ...
    def known_before(self, var: VarRef) -> Variant | None: ...
    def read_back(self, outcome: Outcome) -> None: ...
    def see(self, variables: tuple[VarRef, ...] | list[VarRef]) -> None: ...
    def connect_failed(self, error: ConnectFailed | None) -> None: ...
    def mark_failure(self, error: TransportError) -> None: ...


@dataclass
class EngineParts:
    """The engine's parts a command may change, and how it changes the target."""

    link: Link
    poller: Poller
    publisher: Publisher
    files: FrameFiles
    csv: CsvSink
    switch_target: Callable[[Target | None], None]  # None: disconnect
    plain_policy: WritePolicy  # what ``connect HOST`` (no profile) allows
    #: Publish a confirm question and poll until it is answered (False: No, or cancelled).
    ask_confirm: Callable[[ConfirmWrite, Callable[[], bool]], bool]
    #: This engine's feed to the plant (``publish``), made on first use.
    plant: Callable[[], PlantTap]


class CommandContext:
    """One job's view of the engine (a :class:`JobContext`, and the parts)."""

    def __init__(
        self,
        job: Job,
        parts: EngineParts,
        registry: Registry,
        rules: Target,
        verify: bool,
        stopping: Callable[[], bool],
    ) -> None:
        self.job = job
        self.registry = registry  # the commands this job's engine runs (help lists them)
        self.parts = parts
        self.rules = rules
        self.verify = verify
        self._stopping = stopping

    # ------------------------------------------------------------ JobContext

    @property
    def session(self) -> Session | None:
        return self.parts.link.session

    @property
    def confirm(self) -> Confirm:
        return self._confirm

    def cancelled(self) -> bool:
        return self.job.cancelled() or self._stopping()

    def between(self, until: float, deadline: float) -> None:
        self.parts.poller.poll_until(until, deadline, self.cancelled)

    def known_before(self, var: VarRef) -> Variant | None:
        row = self.parts.poller.watch.rows.get(var)
        return row.variant if row is not None and row.status == OK and not row.stale else None

    def read_back(self, outcome: Outcome) -> None:
        """A watched row shows the value read back at once."""
        row = self.parts.poller.watch.rows.get(outcome.var) if outcome.var is not None else None
        held = outcome.read_back
        if row is not None and held is not None and row.update(held, time.monotonic()):
            self.parts.publisher.show_row(row)

    def see(self, variables: tuple[VarRef, ...] | list[VarRef]) -> None:
        self.parts.poller.see(variables)

    def connect_failed(self, error: ConnectFailed | None) -> None:
        self.parts.link.connect_failed(error)

    def mark_failure(self, error: TransportError) -> None:
        self.parts.link.mark_failure(error)

    # ------------------------------------------------------------ the rest

    def _confirm(
        self, var: VarRef, before: Variant | None, after: Variant, write: Put | Raw
    ) -> bool:
        """Ask the front end (old → new, default No) and keep polling until it answers;
        a cancel or a stop is a No."""
        question = ConfirmWrite(
            self.job.seq,
            str(var),
            plain_value(var, before) if before is not None else None,
            plain_value(var, after),
            write.request.text,
            self.parts.link.described,
            self.rules.label,
        )
        return self.parts.ask_confirm(question, self.cancelled)
