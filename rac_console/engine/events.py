"""What the engine publishes: immutable events, read by the front ends from the outbox.

A front end never reads an engine attribute; everything it shows arrives as one of
these. A :class:`~rac_console.session.Frame` (with its parsed reply) is an event too.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Literal

from ..commands.language import Command, VarRef
from ..commands.latency import LatencySummary
from ..commands.outcome import Outcome
from ..commands.target import WritesShown
from ..protocol import Variant
from ..protocol.text import terminal_safe
from ..session import Frame, Reply, State, TransportError
from ..session.types import ConnectProblem

OK = "OK"
#: The connection as the status line says it: the session's state, lost (found dead
#: while idle, or a poll's connection failed after one had opened), dropped (closed
#: early: backing off), or why connecting failed.
Connection = State | Literal["lost", "dropped"] | ConnectProblem

WAITING = "…"
#: Characters of a profile's label shown (the badges after it must fit 80 columns).
LABEL_WIDTH = 32


def shown_label(label: str, width: int = LABEL_WIDTH) -> str:
    """A profile's label as every front end shows it: escaped, and cut with ``…`` to
    ``width`` characters (present/status.py's ``label_text`` then cuts it to cells)."""
    safe = terminal_safe(label)
    return safe if len(safe) <= width else safe[: width - 1].rstrip() + "…"


@dataclass(frozen=True, slots=True)
class Message:
    """Feedback that is not an exchange: help text, a confirmation, an error."""

    text: str
    level: str = "info"  # info, error


@dataclass(frozen=True, slots=True)
class Measured(Message):
    """``latency``'s figures: shown as their line, kept whole for ``--json``."""

    summary: LatencySummary | None = None

    @classmethod
    def of(cls, what: str, summary: LatencySummary) -> Measured:
        return cls(summary.text(what), "info", summary)


class UiStep(Enum):
    """What only a front end can do."""

    CLEAR = "clear"  # its log or screen
    QUIT = "quit"
    FRAMES_ON = "frames on"  # echo frames (REPL) / show poll frames (console)
    FRAMES_OFF = "frames off"


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


@dataclass(frozen=True, slots=True)
class Status:
    """The figures of the status line and prompt; each replaces the last one."""

    target: str  # "SIMULATOR (built-in)", "LIVE host:port" or "NOT CONNECTED"
    is_simulator: bool
    has_session: bool
    host: str | None
    port: int
    timeout: float
    read_only: bool
    connection: Connection
    retry_at: float | None  # time.monotonic() of the next try, during a backoff
    rtt: float | None
    paused: bool
    watched: int
    interval: float
    period: float
    cycle_seconds: float | None
    polls_per_second: float | None
    interval_met: bool
    record_failure: str | None
    seen: frozenset[tuple[str, int]]
    csv_log: str | None = None  # the CSV log's path while logging
    csv_failure: str | None = None  # why a CSV log failed, kept after a new one starts
    transcript_failure: str | None = None  # why the --log transcript stopped
    profile: str | None = None  # the target profile's name (-H cell3, connect cell3)
    label: str | None = None  # its label: "Cell 3 — welding"
    colour: str | None = None  # its colour, a Rich colour name or #rrggbb
    writes: WritesShown = "open"  # the profile's, or --read-only
    verify: bool = True  # every PUT is read back (off: --no-verify)
    target_id: int = 0  # changes when another target is opened (connect): trends restart
    ever_connected: bool = False  # a connection to this target opened at least once
    recording: str | None = None  # where frames are recorded (--record, record FILE)
    transcribing: str | None = None  # where the transcript goes (--log, transcript FILE)

    def exit_status(self, status: int) -> int:
        """A front end's exit status: 4 (a local I/O error) when it would be 0 but the
        recording, the --log transcript or the CSV log stopped on the way."""
        failed = any(
            failure is not None
            for failure in (self.record_failure, self.transcript_failure, self.csv_failure)
        )
        return 4 if status == 0 and failed else status


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
