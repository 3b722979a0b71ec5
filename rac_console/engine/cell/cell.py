"""A cell: one engine per controller behind one front end, and the lines routed to them.

The RAC spec wants one session per request in flight, so a cell is never one session
shared: each target has its own engine (its session, watch list, poller and rules, on
its own thread) and its own outbox. The cell routes each typed line: ``@NAME LINE`` to
that target, any other line to the current one (``use NAME`` changes it). A write thus
always goes to one controller, named by the line or by the prompt, under that
controller's own rules. Jobs are numbered by one counter for the whole cell, so a
number names one job whichever engine runs it.

A line's way through a cell: :meth:`Cell.enter` queues it (lines run one at a time, in
the order submitted); at its turn it is planned once and carried out by the executor of
routes (:mod:`.routes`, the one ``run`` uses too), each target's part a job in that
target's engine (:mod:`..thread.inbox`); the engine publishes the job's frames, then its
Result, to its outbox, and hands the Result to the cell on its own thread, where the
next line starts. Front ends drain the outboxes when woken; nothing waits for them.

The files are the cell's: one ``--record``, one ``--log`` transcript and one CSV log for
every target, each line naming its target (:class:`~..thread.engine.CellFiles`). The members'
options name no file; the cell opens them before any thread starts, says a failure once
(it stops that file for every target), and closes them once every member has stopped.
"""

from __future__ import annotations

import itertools
import threading
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from ...commands.names import find_name
from ...protocol import InputError
from ...protocol.text import endpoint
from ..published.feedback import Message
from ..published.outbox import Batch, Outbox
from ..setup.options import EngineOptions
from ..setup.where import Where
from ..thread.engine import CellFiles, Engine
from ..thread.surface import EngineLike

#: Gives a target's engine through the agent that holds it (target, options, outbox,
#: the cell's job numbers), or None to run one here (see :class:`Cell`).
Attach = Callable[["Target", EngineOptions, Outbox, Iterator[int]], EngineLike | None]

if TYPE_CHECKING:  # the console's first paint loads none of these
    from ...commands.language import Command
    from ...commands.routing import Route
    from ...commands.target import Target
    from ..commands.registry import Registry
    from ..files.frame_files import FrameFiles
    from ..published.events import Result
    from ..watch.cellcsv import CellCsv
    from .routes import Answer, Done, Line


@dataclass
class _Line:
    """A line submitted, waiting for its turn: typed (``command`` None), or a command a
    front end made for the target ``name`` (None: the current one); once started, the
    route it was planned to (None while it waits)."""

    seq: int
    line: str | None
    command: Command | None = None
    name: str | None = None
    route: Route | None = None


@dataclass(frozen=True)
class Entered:
    """A line handed to the cell: its number, and its route when it started at once
    (None: it waits behind a line running, and is planned at its turn). A front end reads
    the route (where the line writes) instead of planning the line a second time."""

    seq: int
    route: Route | None


@dataclass(frozen=True)
class Member:
    """One target of a cell: the name lines address it by, and its engine."""

    name: str  # the profile's name, or host:port for an address
    target: Target
    engine: EngineLike


def member_name(target: Target) -> str:
    """How a target is named in a cell: its profile's name, else ``host:port``."""
    if target.profile is not None:
        return target.profile.name
    if target.host is None:
        return f"sim:{target.port}"
    return endpoint(target.host, target.port)


class Cell:
    """Start it, submit lines (``@NAME`` or the current target), drain, stop it."""

    def __init__(
        self,
        targets: Sequence[tuple[str, Target]],
        *,
        options: EngineOptions | None = None,
        notify: Callable[[], None] | None = None,
        where: Where = Where.CONSOLE,
        registry: Registry | None = None,
        attach: Attach | None = None,
    ) -> None:
        """One engine per ``(name, target)``, in order; the first is the current one.
        ``attach`` gives a target's engine through an agent, where one holds it (not
        for a cell that keeps one file of its frames for all its targets: those run
        here). Raises InputError when a file cannot be opened (before any thread
        starts)."""
        if not targets:
            raise InputError("a cell needs at least one target")
        self._registry, self.where = registry, where
        self._numbers: Iterator[int] = itertools.count(1)
        #: The cell's own results (``use``, a line for a target it does not have) and
        #: alerts (a file of the cell's that failed). One lock for every outbox of the
        #: cell: a drain takes them all at one instant (see :meth:`drain`).
        self.outbox = Outbox(notify)
        lock = self.outbox.lock
        options = options if options is not None else EngineOptions()
        names = [name for name, _ in targets]
        # One target keeps its own files, exactly as without a cell; several share the
        # cell's, each line naming its target.
        self.files: FrameFiles | None = None
        self.csv: CellCsv | None = None
        if len(targets) > 1:
            from ..files.frame_files import FrameFiles
            from ..watch.cellcsv import CellCsv

            self.files = FrameFiles(options.record, options.transcript, self._alert)
            self.csv = CellCsv(names, self._alert)
            try:
                if options.log_csv:
                    self.csv.wait_for_rows(options.log_csv)
            except InputError:
                self.files.close()
                raise
        files, csv = self.files, self.csv
        own = (
            options
            if files is None
            else replace(options, record=None, transcript=None, log_csv=None)
        )
        named = {  # a name the user (or the demo) gave is the target's name in topics too
            name: replace(own, plant_name=name) if name != member_name(target) else own
            for name, target in targets
        }

        def engine_for(place: int, name: str, target: Target) -> EngineLike:
            outbox = Outbox(notify, lock)
            if attach is not None and files is None:
                attached = attach(target, named[name], outbox, self._numbers)
                if attached is not None:
                    return attached
            return Engine(
                target=target,
                options=named[name],
                outbox=outbox,
                where=where,
                registry=registry,
                numbers=self._numbers,
                cell_files=(
                    None
                    if files is None or csv is None
                    else CellFiles(name, files.view(name, place), csv)
                ),
            )

        self.members: tuple[Member, ...] = tuple(
            Member(name, target, engine_for(place, name, target))
            for place, (name, target) in enumerate(targets, 1)
        )
        self._queue_parts()

    def _queue_parts(self) -> None:
        from .routes import Routes

        #: Plans each line once and carries its route out, the engines running the
        #: commands (the same executor as ``run``'s, whose sessions run them inline).
        self.routes = Routes(
            _Engines(self),
            [(member.name, member.target) for member in self.members],
            lambda: self.registry,
            self.where,
        )
        self._lock = threading.RLock()
        #: Lines submitted, waiting for their turn: the route of a line depends on the
        #: ``use`` before it, and a cell runs one line at a time, whatever target each
        #: names. The next starts when the last has answered, on the thread it ended on.
        self._lines: deque[_Line] = deque()
        self._running: int | None = None  # the number of the line running now
        self._pumping = False  # a thread is taking lines from the queue (under the lock)
        self._dropped: list[_Line] = []  # cancelled behind the line running: said after it

    @classmethod
    def of(cls, engine: EngineLike, name: str | None = None) -> Cell:
        """A cell of one engine made already (a single target, exactly as before)."""
        cell = cls.__new__(cls)
        cell._registry, cell.where = None, engine.where
        cell._numbers = engine.numbers
        cell.outbox = Outbox(engine.outbox.notify, engine.outbox.lock)
        cell.files = cell.csv = None
        member = Member(name or member_name(engine.target), engine.target, engine)
        cell.members = (member,)
        cell._queue_parts()
        return cell

    @property
    def outboxes(self) -> tuple[Outbox, ...]:
        """The cell's own outbox, then each member's: a front end sets their notify."""
        return (self.outbox, *(member.engine.outbox for member in self.members))

    @property
    def current(self) -> str:
        """The target the lines without ``@NAME`` go to (``use NAME`` changes it)."""
        return self.routes.current

    @property
    def single(self) -> bool:
        """One target: every front end looks and behaves exactly as without a cell."""
        return len(self.members) == 1

    def set_notify(self, notify: Callable[[], None] | None) -> None:
        """Who is woken when anything is published (the front end's loop)."""
        self.outbox.notify = notify
        for member in self.members:
            member.engine.outbox.notify = notify

    # ------------------------------------------------------------------ members

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(member.name for member in self.members)

    def member(self, name: str | None = None) -> Member:
        """The target named ``name`` (None: the current one); InputError naming the
        open targets when there is none by that name."""
        found = find_name(self.names, self.current if name is None else name)
        if found is None:
            from ...commands.cells import not_open

            raise not_open(str(name), self.names)
        return self.members[self.names.index(found)]

    def start(self, connect: bool = True) -> None:
        for member in self.members:
            member.engine.start(connect)

    def stop(self, timeout: float = 5.0) -> None:
        """Stop every member, then close the cell's files (no member writes them now)."""
        for member in self.members:
            member.engine.stop(timeout)
        if self.files is not None:
            self.files.close()
        if self.csv is not None:
            self.csv.close()

    @property
    def registry(self) -> Registry:
        """The commands the cell's lines are parsed with: its engines'."""
        return self._registry or self.members[0].engine.registry

    def _alert(self, text: str) -> None:
        """A file of the cell's failed (from any member's thread): said once, here."""
        from ..published.events import Alert

        self.outbox.put(Alert(text))

    # ------------------------------------------------------------------ jobs

    def submit(self, line: str) -> int:
        """Queue a typed line; it is planned (:mod:`rac_console.commands.routing`) when
        every line before it has ended, so lines run one at a time, in the order typed,
        whatever target each names. Its Result carries the number returned (from its
        target's outbox, or the cell's for a line the cell answers itself)."""
        return self.enter(line).seq

    def submit_command(
        self, command: Command, line: str | None = None, name: str | None = None
    ) -> int:
        """Queue a command a front end made (Space on a row of ``name``'s table), in
        turn with the typed lines; run as it is, never parsed."""
        return self.enter(line, command, name).seq

    def enter(
        self, line: str | None, command: Command | None = None, name: str | None = None
    ) -> Entered:
        """:meth:`submit` (``command`` None) or :meth:`submit_command`, saying the
        route the line was planned to when it started at once (the console's guard of
        the keys typed ahead of a write's question reads it)."""
        with self._lock:  # numbered in the order queued: answers are read in that order
            item = _Line(next(self._numbers), line, command, name)
            self._lines.append(item)
        self._pump()
        return Entered(item.seq, item.route)

    def _pump(self) -> None:
        """Start the next lines while none runs: those the cell answers itself at once,
        then the first a target runs (the next waits for its answer). On the thread that
        submitted a line, or the one a line ended on; a line answered at once while the
        queue is being taken is followed by the next in the same loop, not a deeper one."""
        with self._lock:
            if self._pumping:
                return
            self._pumping = True
            try:
                while self._running is None and self._lines:
                    item = self._lines.popleft()
                    self._running = item.seq
                    self._start(item)
            finally:
                self._pumping = False

    def _start(self, item: _Line) -> None:
        """Plan one line, once, and carry it out (under the lock)."""
        from .routes import Answer, Line

        line = Line(item.seq, item.line, item.command, item.name)
        try:
            item.route = self.routes.plan(line)
            self.routes.execute(item.route, line, self._answered)
        except Exception as exc:  # a bug must not stop the queue, nor the thread it is on
            said = Message(f"internal error: {exc!r}", "error")
            self._answered(Answer(line, item.command, ((None, (said,)),)))

    def _answered(self, answer: Answer) -> None:
        """A line's answer (on the thread it ended on): said by the cell unless its one
        target's engine said it already; then the next line starts."""
        from ..published.events import Result

        line = answer.line
        if answer.by is None:
            self.outbox.put(Result(line.seq, answer.feedback, line.text, answer.command))
        with self._lock:
            if self._running != line.seq:
                return
            self._running = None
            self._say_dropped()
        self._pump()

    def cancel(self, queued: bool = False) -> None:
        """Esc, Ctrl-C: the running line stops on every target, and the lines queued
        behind it are not run (each answered so); next to moving machinery, stop means
        everywhere. (``queued`` is kept for the callers: the cell's queue always goes.)"""
        with self._lock:
            self._dropped.extend(self._lines)
            self._lines.clear()
            if self._running is None:
                self._say_dropped()
        for member in self.members:
            member.engine.cancel(queued)

    def _say_dropped(self) -> None:
        """The lines a cancel dropped, answered once the line running has ended (so
        their answers come after its, in the order typed)."""
        from ..published.events import Result
        from ..thread.engine import NOT_RUN

        dropped, self._dropped = self._dropped, []
        for item in dropped:
            said = (Message(NOT_RUN, "error"),)
            self.outbox.put(Result(item.seq, said, item.line, item.command))

    def answer_confirm(self, seq: int, yes: bool) -> None:
        """The answer to a ConfirmWrite: its number names one job in the cell."""
        for member in self.members:
            member.engine.answer_confirm(seq, yes)

    def set_poll_frames(self, shown: bool) -> None:
        for member in self.members:
            member.engine.set_poll_frames(shown)

    def drain(self) -> list[tuple[str | None, Batch]]:
        """Everything published since the last drain, taken at one instant: the cell's
        own results (None), then each target's batch, by name; when several hold
        answers, cut so that the answers come in the order the lines were submitted
        (:mod:`.answer_order`). The queue of lines moves without it."""
        batches = Outbox.drain_together(self.outboxes)
        drained: list[tuple[str | None, Batch]] = [(None, batches[0])]
        drained.extend((m.name, b) for m, b in zip(self.members, batches[1:], strict=True))
        if not any(batch.events for _, batch in drained):
            return drained  # the first paint loads no event class
        from .answer_order import in_answer_order

        return in_answer_order(drained)


class _Engines:
    """A cell's :class:`~.routes.Targets`: each target's engine runs a command as a
    job, on its own thread; the feedback comes back on that thread."""

    def __init__(self, cell: Cell) -> None:
        self._cell = cell

    def run(self, name: str, command: Command, line: Line, done: Done, whole: bool) -> None:
        """A job on ``name``'s engine; ``whole``: numbered as the line and published by
        the engine (its Result is the line's answer, with the frames before it); else a
        step of the cell's answer, numbered on its own and handed to ``done`` alone."""
        engine = self._cell.member(name).engine

        def then(result: Result) -> None:
            done(result.feedback)

        if whole:
            engine.submit_command(command, line.text, line.seq, then=then)
        else:
            engine.submit_command(command, then=then, publish=False)
