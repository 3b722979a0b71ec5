"""The status line's figures, as the engine publishes them: one immutable snapshot.

Apart from the other events (:mod:`.events`) so that the console can paint its first
screen, whose status line names the target, without loading the command language, the
sessions and the outcomes those carry: this module's imports are for the type checker.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, Union

from ...protocol.text import terminal_safe

if TYPE_CHECKING:
    from ...commands.target import Target, WritesShown
    from ...session.types import ConnectProblem, State
    from ..setup.options import EngineOptions

#: The connection as the status line says it: the session's state, lost (found dead
#: while idle, or a poll's connection failed after one had opened), dropped (closed
#: early: backing off), why connecting failed, or that the engine's thread has ended
#: on an internal error (nothing polls or answers any more).
Connection = Union["State", Literal["lost", "dropped", "engine stopped"], "ConnectProblem"]

#: A watched row's status when its last read came back good, and before its first.
OK = "OK"
WAITING = "…"
#: Characters of a profile's label shown (the badges after it must fit 80 columns).
LABEL_WIDTH = 32


def shown_label(label: str, width: int = LABEL_WIDTH) -> str:
    """A profile's label as every front end shows it: escaped, and cut with ``…`` to
    ``width`` characters (present/status.py's ``label_text`` then cuts it to cells)."""
    safe = terminal_safe(label)
    return safe if len(safe) <= width else safe[: width - 1].rstrip() + "…"


def described(host: str | None, port: int) -> str:
    """The status line's name of a target that is open: no host is the simulator."""
    return "SIMULATOR (built-in)" if host is None else f"LIVE {host}:{port}"


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
    reads: tuple[int, int, int] = (0, 0, 0)  # watched reads: ok, error, no reply
    #: The MQTT broker the watched values go to, by its state: connected, connecting,
    #: away, silent, refused, stopped; None: not publishing.
    broker: str | None = None
    #: "via agent" when the engine runs in the agent (the status line says so).
    via: str | None = None

    def exit_status(self, status: int) -> int:
        """A front end's exit status: 4 (a local I/O error) when it would be 0 but the
        recording, the --log transcript or the CSV log stopped on the way."""
        failed = any(
            failure is not None
            for failure in (self.record_failure, self.transcript_failure, self.csv_failure)
        )
        return 4 if status == 0 and failed else status


def status_before_start(rules: Target, options: EngineOptions) -> Status:
    """The status of an engine whose parts are not made yet (a front end paints it before
    the engine starts): as the parts begin, no session, nothing watched, no file."""
    profile = rules.profile
    return Status(
        target="NOT CONNECTED",
        is_simulator=False,
        has_session=False,
        host=None,
        port=5006,
        timeout=options.timeout,
        read_only=rules.read_only,
        connection="closed",
        retry_at=None,
        rtt=None,
        paused=False,
        watched=0,
        interval=options.interval,
        period=options.interval,
        cycle_seconds=None,
        polls_per_second=None,
        interval_met=True,
        record_failure=None,
        transcript_failure=None,
        csv_log=None,
        csv_failure=None,
        seen=frozenset(),
        profile=profile.name if profile is not None else None,
        label=profile.label if profile is not None else None,
        colour=profile.colour if profile is not None else None,
        writes=rules.writes,
        verify=options.verify,
    )
