"""What the engine publishes: immutable events, read by the front ends from the outbox.

A front end never reads an engine attribute; everything it shows arrives as one of
these. A :class:`~rac_console.session.Frame` (with its parsed reply) is an event too.
The status line's figures (:class:`Status`) live in :mod:`.status`, which the console's
first paint loads without the rest.
"""

from __future__ import annotations

from dataclasses import dataclass

from ...commands.language import Command, VarRef
from ...commands.latency import LatencySummary
from ...commands.outcome import Outcome
from ...protocol import Variant
from ...session import Frame, Reply, TransportError
from .feedback import Message, UiStep
from .status import LABEL_WIDTH, OK, WAITING, Connection, Status, shown_label


@dataclass(frozen=True, slots=True)
class Measured(Message):
    """``latency``'s figures: shown as their line, kept whole for ``--json``."""

    summary: LatencySummary | None = None

    @classmethod
    def of(cls, what: str, summary: LatencySummary) -> Measured:
        return cls(summary.text(what), "info", summary)


Feedback = Outcome | Message | UiStep


@dataclass(frozen=True, slots=True)
class Result:
    """What came of the command submitted as ``seq``: shown in the order submitted."""

    seq: int  # 0: not the answer to a submitted line (the first connection's failure)
    feedback: tuple[Feedback, ...]
    line: str | None = None
    command: Command | None = None  # the line as parsed, once, by the engine


@dataclass(frozen=True, slots=True)
class Note:
    """A mark in the frame log: a connection gap, a request that got no trustworthy reply."""

    text: str
    time: float


@dataclass(frozen=True, slots=True)
class Alert:
    """Something to tell the user at once, whatever they are doing: a recording stopped."""

    text: str
    #: A local file failed (the CLI's exit status 4); False: news, such as the plant's.
    local_failure: bool = True


@dataclass(frozen=True, slots=True)
class RowView:
    """One watched variable as it stands: what a table shows. Replaces the last one."""

    var: VarRef
    label: str
    variant: Variant | None
    status: str
    stale: bool
    changed_at: float | None
    every: float | None

    @property
    def key(self) -> str:
        return str(self.var)


#: A watched variable's read in a cycle: the reply, or how the exchange failed.
Reading = tuple[VarRef, "Reply | TransportError"]


@dataclass(frozen=True, slots=True)
class Cycle:
    """One poll cycle ended: what it read, for trends and the CSV log.

    Published only by an engine made with ``cycles=True`` (the console); each row
    polled in the cycle appears once, with its good value or None when the poll failed.
    """

    time: float  # time.time() when the cycle ended (wall clock, for timestamps)
    monotonic: float  # time.monotonic() then (for windows of seconds)
    samples: tuple[tuple[VarRef, Variant | None], ...]
    target_id: int = 0  # the target polled (Status.target_id): an old one's is dropped
    #: How each read went (its reply, or the failure): a CLI watch's lines are made of
    #: them. A cycle cut short by an unreachable controller ends with that failure.
    readings: tuple[Reading, ...] = ()


#: A yes within this many seconds of a confirm question is not taken as its answer (the
#: console's dialog and the REPL alike): it was typed ahead, or pasted over a slow link.
CONFIRM_GUARD_SECONDS = 0.4


@dataclass(frozen=True, slots=True)
class ConfirmWrite:
    """A write on a ``confirm`` target waits for a yes: the front end asks old → new
    (default No) and answers with :meth:`Engine.answer_confirm` ``(seq, yes)``.

    Until it is answered the engine keeps polling and runs nothing else; Esc (the
    engine's cancel) counts as No."""

    seq: int  # the submitted line's number, as its Result will carry
    var: str  # "I10", or the raw line's variable
    before: str | None  # the value now, as text ("14"); None when it could not be read
    after: str  # the value to write, as text
    request: str  # the PUT's wire text
    target: str  # "LIVE 192.168.0.1:5006"
    label: str | None  # the profile's label


Event = Frame | Note | Alert | Result | Cycle | ConfirmWrite

__all__ = [
    "CONFIRM_GUARD_SECONDS",
    "LABEL_WIDTH",
    "OK",
    "WAITING",
    "Alert",
    "ConfirmWrite",
    "Connection",
    "Cycle",
    "Event",
    "Feedback",
    "Measured",
    "Message",
    "Note",
    "Reading",
    "Result",
    "RowView",
    "Status",
    "UiStep",
    "shown_label",
]
