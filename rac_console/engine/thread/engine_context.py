"""The engine's :class:`~..commands.context.CommandContext`: one job's view of the engine.

It holds the engine's parts privately and does to them what a command asks, one method
per thing (:mod:`..commands.context` lists them); a handler never reaches a part. Made by the
engine for each job, and used on the engine's thread alone, as the parts are.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Self

from ...commands.routing import WriteTrait
from ..commands.context import CommandContext, CsvLogState, FrameFileKind, LogFile
from ..exchange.controller import Controller
from ..exchange.gate import WriteGate
from ..exchange.writes import plain_value
from ..published.events import OK, ConfirmWrite

if TYPE_CHECKING:
    from ...commands.language import Put, Raw, VarRef
    from ...commands.outcome import Outcome
    from ...commands.plant import MqttAddress
    from ...commands.policy import WritePolicy
    from ...commands.target import Target
    from ...protocol import Variant
    from ...session import ConnectFailed, TransportError
    from ..commands.registry import Registry
    from ..files.frame_files import FrameFiles
    from ..polling.link import Link
    from ..polling.plant_tap import PlantTap
    from ..polling.poller import Poller
    from ..polling.publisher import Publisher
    from ..published.events import RowView
    from ..watch.csvlog import CsvLog
    from ..watch.csvsink import CsvSink
    from .job import Job

#: How often a write waiting for its confirmation looks for the answer (polling between).
CONFIRM_CHECK_EVERY = 0.02


@dataclass
class EngineParts:
    """The engine's parts, and what only the engine itself can do for a job."""

    link: Link
    poller: Poller
    publisher: Publisher
    files: FrameFiles
    csv: CsvSink
    #: Open another target and take its rules (None: close the target).
    switch_target: Callable[[Target | None], None]
    plain_policy: WritePolicy  # what ``connect HOST`` (no profile) allows
    #: This engine's feed to the plant (``publish``), made on first use.
    plant: Callable[[], PlantTap]
    #: The front end's answer to the confirm question of that number, taken (None: none yet).
    take_answer: Callable[[int], bool | None]
    publish_status: Callable[[], None]  # now, whatever was published last


class EngineContext:
    """One job's :class:`~..commands.context.CommandContext` (and so its
    :class:`~..commands.context.JobContext`)."""

    def __init__(
        self,
        job: Job,
        parts: EngineParts,
        registry: Registry,
        rules: Target,
        verify: bool,
        stopping: Callable[[], bool],
    ) -> None:
        self._job = job
        self._parts = parts
        self._registry = registry  # the commands this job's engine runs (help lists them)
        self._rules = rules
        self._verify = verify
        self._stopping = stopping
        #: The command whose job this is, and what it declares (see :meth:`declaring`).
        self._declared: tuple[str, WriteTrait] = ("", WriteTrait.NEVER)

    # ------------------------------------------------------------ JobContext

    @property
    def controller(self) -> Controller | None:
        session = self._parts.link.session
        return Controller(session, self._gate()) if session is not None else None

    @property
    def rules(self) -> Target:
        return self._rules

    def declaring(self, name: str, writes: WriteTrait) -> Self:
        declared = copy.copy(self)
        declared._declared = (name, writes)
        return declared

    def cancelled(self) -> bool:
        return self._job.cancelled() or self._stopping()

    def between(self, until: float, deadline: float) -> None:
        self._parts.poller.poll_until(until, deadline, self.cancelled)

    def _gate(self) -> WriteGate:
        """This job's write gate: the target's rules as the job began, what its command
        declares, the confirm question put to the front end, the watched value before."""
        name, writes = self._declared
        rules = self._rules
        return WriteGate(
            rules.policy,
            writes,
            name,
            rules.read_only,
            self._verify,
            self._known_before,
            self._confirm,
            self.cancelled,
        )

    def _known_before(self, var: VarRef) -> Variant | None:
        row = self._parts.poller.watch.rows.get(var)
        return row.variant if row is not None and row.status == OK and not row.stale else None

    def read_back(self, outcome: Outcome) -> None:
        """A watched row shows the value read back at once."""
        row = self._parts.poller.watch.rows.get(outcome.var) if outcome.var is not None else None
        held = outcome.read_back
        if row is not None and held is not None and row.update(held, time.monotonic()):
            self._parts.publisher.show_row(row)

    def see(self, variables: tuple[VarRef, ...] | list[VarRef]) -> None:
        self._parts.poller.see(variables)

    def connect_failed(self, error: ConnectFailed | None) -> None:
        self._parts.link.connect_failed(error)

    def mark_failure(self, error: TransportError) -> None:
        self._parts.link.mark_failure(error)

    def engine_context(self) -> CommandContext:
        return self

    # ------------------------------------------------------------ the target

    @property
    def plain_policy(self) -> WritePolicy:
        return self._parts.plain_policy

    def switch_target(self, target: Target) -> None:
        self._parts.switch_target(target)

    def disconnect(self) -> None:
        parts = self._parts
        parts.switch_target(None)
        for row in parts.poller.watch.mark_all("DISCONNECTED"):
            parts.publisher.show_row(row)

    # ------------------------------------------------------------ the frame log

    def note(self, text: str) -> None:
        self._parts.publisher.note(text)

    def alert(self, text: str) -> None:
        self._parts.publisher.alert(text)

    # ------------------------------------------------------------ the watch list

    def watch(self, variables: Sequence[VarRef], label: str, every: float | None) -> int:
        poller, publisher = self._parts.poller, self._parts.publisher
        added = poller.add_rows(list(variables), label, every)  # bounded there
        for var in variables:
            publisher.show_row(poller.watch.rows[var])
        poller.see(list(variables))
        poller.wake()
        return added

    def unwatch(self, variables: Sequence[VarRef]) -> list[VarRef]:
        removed = self._parts.poller.watch.remove(list(variables))
        self._parts.publisher.remove_rows(removed)
        return removed

    def watched_rows(self) -> list[RowView]:
        return [row.view() for row in self._parts.poller.watch.rows.values()]

    @property
    def interval(self) -> float:
        return self._parts.poller.interval

    def set_interval(self, seconds: float) -> None:
        self._parts.poller.set_interval(seconds)  # bounded there

    def pause_polling(self, paused: bool) -> bool:
        poller = self._parts.poller
        poller.set_paused(paused)
        return poller.paused

    # ------------------------------------------------------------ the files

    def frame_file(self, kind: FrameFileKind) -> str | None:
        return self._parts.files.path(kind)

    def start_frame_file(self, kind: FrameFileKind, path: str) -> None:
        self._parts.files.set(kind, path)
        self._changed()

    def stop_frame_file(self, kind: FrameFileKind) -> str | None:
        files = self._parts.files
        running = files.running(kind)
        if running is None:
            return None
        running.close()
        files.set(kind, None)
        self._changed()
        return running.path

    @property
    def shares_frame_files(self) -> bool:
        return self._parts.files.shared

    def csv_log(self) -> CsvLogState:
        sink = self._parts.csv
        cell = sink.cell
        if cell is None:
            return CsvLogState(False, sink.path, log_file(sink.log))
        log = cell.log
        return CsvLogState(True, cell.path, log_file(log), tuple(cell.waiting_for()))

    def start_csv_log(self, path: str) -> LogFile | None:
        sink, rows = self._parts.csv, self._parts.poller.watch.rows
        if sink.cell is not None or not rows:
            sink.wait_for_rows(path)
            return None
        return log_file(sink.start(path, list(rows)))

    def stop_csv_log(self) -> LogFile | None:
        return log_file(self._parts.csv.stop())

    # ------------------------------------------------------------ the plant

    def plant_name(self) -> str:
        return self._parts.plant().name

    def publishing_to(self) -> str | None:
        return self._parts.plant().publishing

    def publish_to(self, address: MqttAddress) -> str:
        said = self._parts.plant().publish_to(address, self.watched_rows())
        self._changed()
        return said

    def stop_publishing(self) -> str | None:
        stopped = self._parts.plant().stop_publishing()
        self._changed()
        return stopped

    # ------------------------------------------------------------ the commands

    def help_lines(self, topic: str | None) -> list[str]:
        return self._registry.help_lines(topic)

    # ------------------------------------------------------------ inside

    def _changed(self) -> None:
        """The status line shows what changed when the engine's loop next turns."""
        self._parts.publisher.status_dirty = True

    def _confirm(
        self, var: VarRef, before: Variant | None, after: Variant, write: Put | Raw
    ) -> bool:
        """Ask the front end (old → new, default No) and keep polling until it answers;
        a cancel or a stop is a No."""
        question = ConfirmWrite(
            self._job.seq,
            str(var),
            plain_value(var, before) if before is not None else None,
            plain_value(var, after),
            write.request.text,
            self._parts.link.described,
            self._rules.label,
        )
        return self._ask(question)

    def _ask(self, question: ConfirmWrite) -> bool:
        """Publish the question and poll until the front end answers (False: No, or
        cancelled)."""
        parts = self._parts
        parts.take_answer(question.seq)  # an answer kept from before is not to this one
        if self.cancelled():  # cancelled already: no question about a write that ended
            return False
        parts.publisher.emit(question)
        parts.publish_status()
        parts.publisher.flush()
        while not self.cancelled():
            answer = parts.take_answer(question.seq)
            if answer is not None:
                return answer
            until = time.perf_counter() + CONFIRM_CHECK_EVERY
            parts.poller.poll_until(until, float("inf"), self.cancelled)
            parts.publisher.flush()
        return False


def log_file(log: CsvLog | None) -> LogFile | None:
    """What a command tells of a CSV log."""
    if log is None:
        return None
    variables = tuple(log.variables)
    return LogFile(log.path, variables, log.rows, log.appending, log.failure)
