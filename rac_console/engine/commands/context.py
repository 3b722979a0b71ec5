"""What a command's handler may use: its job, the target's rules, and (in an engine)
what it may do to the engine, one method per thing. Handlers never see the engine
itself, nor its parts (the link, the poller, the publisher, the files, the CSV sink),
nor the session: they read and write through :attr:`JobContext.controller`, whose
writes cross the job's write gate (:mod:`..exchange.gate`).

:class:`JobContext` is enough for the commands that also run in ``rac-console run``
and at the command line (an exchange, a wait): the CLI provides one over its own
session (:class:`~.session_context.SessionContext`). :class:`CommandContext` is the
engine's, for every command; :class:`~..thread.engine_context.EngineContext` implements it.
A command's entry says which of the two its handler takes (:mod:`.registry`), and
mypy checks the handler against it.

Nothing here runs: these are the types handlers are written against.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, Protocol, Self

if TYPE_CHECKING:
    from ...commands.language import VarRef
    from ...commands.outcome import Outcome
    from ...commands.plant import MqttAddress
    from ...commands.policy import WritePolicy
    from ...commands.routing import WriteTrait
    from ...commands.target import Target
    from ...session import ConnectFailed, TransportError
    from ..exchange.controller import Controller
    from ..published.events import RowView

#: The files frames go to besides the screen (``record``, ``transcript``).
FrameFileKind = Literal["record", "transcript"]


@dataclass(frozen=True)
class LogFile:
    """A CSV log as a command tells of it."""

    path: str
    variables: tuple[VarRef, ...]  # its columns
    rows: int  # written so far
    appending: bool = False  # to a file that had the same columns
    failure: str | None = None  # its header could not be written


@dataclass(frozen=True)
class CsvLogState:
    """Where the CSV log stands."""

    cell: bool  # the cell's one log, for every target (whichever runs ``log``)
    path: str | None  # where rows go, or will from a poll cycle; None: not logging
    log: LogFile | None  # the log being written (None: none, or one still waiting)
    waiting_for: tuple[str, ...] = ()  # a cell's targets whose first poll cycle it awaits


class JobContext(Protocol):
    """What an exchange or a wait needs, wherever it runs."""

    @property
    def controller(self) -> Controller | None:
        """The target, to read and (through this job's write gate) to write; None: not
        connected. Made from the job's command spec: a command declared never to write
        (its traits) has every write refused at the gate, nothing sent."""
        ...

    @property
    def rules(self) -> Target: ...

    def declaring(self, name: str, writes: WriteTrait) -> Self:
        """This context for a job of the command ``name``, which declares ``writes``
        (its spec's traits; :meth:`~.registry.Spec.run` asks it). A context never
        declared lets no write out."""
        ...

    def cancelled(self) -> bool: ...
    def between(self, until: float, deadline: float) -> None: ...
    def read_back(self, outcome: Outcome) -> None: ...
    def see(self, variables: tuple[VarRef, ...] | list[VarRef]) -> None: ...
    def connect_failed(self, error: ConnectFailed | None) -> None: ...
    def mark_failure(self, error: TransportError) -> None: ...

    def engine_context(self) -> CommandContext | None:
        """This job's engine's context, for a command that needs one (None: the job
        runs on a plain session, as ``rac-console run`` and a one-shot command do)."""
        ...


class CommandContext(JobContext, Protocol):
    """What the engine's commands do to it (the console's and the REPL's, and the
    command line's ``watch``): one method per thing, run on the engine's thread. A
    method that changes what the status line shows has it published."""

    # ------------------------------------------------------------ the target

    @property
    def plain_policy(self) -> WritePolicy:
        """What ``connect HOST`` (no profile) allows: the engine's rules at its start."""
        ...

    def switch_target(self, target: Target) -> None:
        """Close the target, open ``target`` (and its rules) in its place."""
        ...

    def disconnect(self) -> None:
        """Close the target and stop polling: every watched row says DISCONNECTED."""
        ...

    # ------------------------------------------------------------ the frame log

    def note(self, text: str) -> None:
        """A mark in the frame log (and the transcript)."""
        ...

    def alert(self, text: str) -> None:
        """Said at once, whatever the user is doing."""
        ...

    # ------------------------------------------------------------ the watch list

    def watch(self, variables: Sequence[VarRef], label: str, every: float | None) -> int:
        """Watch ``variables`` (a label or ``every`` given again updates a row), shown and
        polled at once; how many were not watched before. InputError, nothing changed,
        past the engine's bounds (a served console's: ``every`` under its floor, more
        rows than its cap)."""
        ...

    def unwatch(self, variables: Sequence[VarRef]) -> list[VarRef]:
        """Stop watching ``variables`` (none given: all); the ones that were watched."""
        ...

    def watched_rows(self) -> list[RowView]:
        """The watched variables as they stand, in the table's order."""
        ...

    @property
    def interval(self) -> float:
        """Seconds between poll cycles (a row's own ``every`` aside)."""
        ...

    def set_interval(self, seconds: float) -> None:
        """Poll every ``seconds`` from now on (the next cycle starts at once); InputError,
        nothing changed, under the engine's bounds' floor."""
        ...

    def pause_polling(self, paused: bool) -> bool:
        """Stop (True) or restart (False) polling the watched variables; whether
        polling is paused now."""
        ...

    # ------------------------------------------------------------ the files

    def frame_file(self, kind: FrameFileKind) -> str | None:
        """Where the ``kind`` file goes; None: not running."""
        ...

    def start_frame_file(self, kind: FrameFileKind, path: str) -> None:
        """Write every frame to ``path`` from now on (InputError: it cannot be opened,
        or a cell's runs already)."""
        ...

    def stop_frame_file(self, kind: FrameFileKind) -> str | None:
        """Close the ``kind`` file; where it went (None: none was running)."""
        ...

    @property
    def shares_frame_files(self) -> bool:
        """Whether the frame files are a cell's (started and stopped for every target)."""
        ...

    def csv_log(self) -> CsvLogState:
        """Where the CSV log stands now."""
        ...

    def start_csv_log(self, path: str) -> LogFile | None:
        """Log the watched values to ``path``: from now on, the watched variables its
        columns, or (None) from the first poll cycle with rows (in a cell: once every
        target has polled). InputError: the file cannot be used."""
        ...

    def stop_csv_log(self) -> LogFile | None:
        """End the CSV log, or the one waiting for its first cycle; the one ended."""
        ...

    # ------------------------------------------------------------ the plant

    def plant_name(self) -> str:
        """This target's name in the plant's topics and labels."""
        ...

    def publishing_to(self) -> str | None:
        """Where the watched values are published; None: nowhere."""
        ...

    def publish_to(self, address: MqttAddress) -> str:
        """Publish the watched values to ``address`` from now on, starting with the rows
        as they stand; what was said of it (InputError: it cannot be done)."""
        ...

    def stop_publishing(self) -> str | None:
        """Stop publishing; what was stopped (None: nothing was published)."""
        ...

    # ------------------------------------------------------------ the commands

    def help_lines(self, topic: str | None) -> list[str]:
        """``help`` of the commands this engine runs (``topic``: one of them)."""
        ...
