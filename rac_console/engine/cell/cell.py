"""A cell: one engine per controller behind one front end, and the lines routed to them.

The RAC spec wants one session per request in flight, so a cell is never one session
shared: each target has its own engine (its session, watch list, poller and rules, on
its own thread) and its own outbox. The cell routes each typed line: ``@NAME LINE`` to
that target, any other line to the current one (``use NAME`` changes it). A write thus
always goes to one controller, named by the line or by the prompt, under that
controller's own rules. Jobs are numbered by one counter for the whole cell, so a
number names one job whichever engine runs it.

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
from ...protocol.text import endpoint, terminal_safe
from ..published.feedback import Message
from ..published.outbox import Batch, Outbox
from ..setup.options import EngineOptions
from ..setup.where import Where
from ..thread.engine import CellFiles, Engine

if TYPE_CHECKING:  # the console's first paint loads none of these
    from ...commands.language import Command, Wait
    from ...commands.outcome import Outcome
    from ...commands.routing import Chained, Route, SwitchCurrent
    from ...commands.target import Target
    from ..commands.registry import Registry
    from ..files.frame_files import FrameFiles
    from ..published.events import Event, Feedback, Result
    from ..watch.cellcsv import CellCsv


@dataclass
class _Chain:
    """A ``wait ... after @NAME ...`` under way: the first target's wait, then this
    one's; the front end awaits ``seq``."""

    seq: int
    line: str | None
    command: Wait
    first: str  # the target waited for first
    second: str  # the target the line ran on
    first_outcome: Outcome | None = None


@dataclass
class _Gather:
    """A line run by every target of the cell; the front end awaits ``seq``, answered
    once every target's result is in (in the cell's order)."""

    seq: int
    line: str | None
    command: Command
    waiting: dict[str, tuple[Feedback, ...] | None]  # by target: its feedback, once in


@dataclass(frozen=True)
class _Line:
    """A line submitted, waiting for its turn: typed (``command`` None), or a command a
    front end made for the target ``name`` (None: the current one)."""

    seq: int
    line: str | None
    command: Command | None = None
    name: str | None = None


@dataclass(frozen=True)
class Member:
    """One target of a cell: the name lines address it by, and its engine."""

    name: str  # the profile's name, or host:port for an address
    target: Target
    engine: Engine


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
    ) -> None:
        """One engine per ``(name, target)``, in order; the first is the current one.
        Raises InputError when a file cannot be opened (before any thread starts)."""
        if not targets:
            raise InputError("a cell needs at least one target")
        self._registry, self.where = registry, where
        self._numbers: Iterator[int] = itertools.count(1)
        #: The cell's own results (``use``, a line for a target it does not have) and
        #: alerts (a file of the cell's that failed).
        self.outbox = Outbox(notify)
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
        self.members: tuple[Member, ...] = tuple(
            Member(
                name,
                target,
                Engine(
                    target=target,
                    options=named[name],
                    outbox=Outbox(notify),
                    where=where,
                    registry=registry,
                    numbers=self._numbers,
                    cell_files=(
                        None
                        if files is None or csv is None
                        else CellFiles(name, files.view(name, place), csv)
                    ),
                ),
            )
            for place, (name, target) in enumerate(targets, 1)
        )
        self.current = self.members[0].name
        self._queue_parts()

    def _queue_parts(self) -> None:
        self._lock = threading.RLock()
        self._lines: deque[_Line] = deque()  # submitted, waiting for their turn
        self._running: int | None = None  # the number of the line running now
        self._dropped: list[_Line] = []  # cancelled behind the line running: said after it
        self._chains: dict[int, _Chain] = {}  # by the number of the job awaited now
        self._gathers: dict[int, _Gather] = {}  # by the number of each member's job

    @classmethod
    def of(cls, engine: Engine, name: str | None = None) -> Cell:
        """A cell of one engine made already (a single target, exactly as before)."""
        cell = cls.__new__(cls)
        cell._registry, cell.where = None, engine.where
        cell._numbers = engine.numbers
        cell.outbox = Outbox(engine.outbox.notify)
        cell.files = cell.csv = None
        member = Member(name or member_name(engine.target), engine.target, engine)
        cell.members = (member,)
        cell.current = member.name
        cell._queue_parts()
        return cell

    @property
    def outboxes(self) -> tuple[Outbox, ...]:
        """The cell's own outbox, then each member's: a front end sets their notify."""
        return (self.outbox, *(member.engine.outbox for member in self.members))

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
        """Queue a typed line; it is routed (:mod:`rac_console.commands.routing`) when
        every line before it has ended, so lines run one at a time, in the order typed,
        whatever target each names. Its Result carries the number returned (from its
        target's outbox, or the cell's for a line the cell answers itself)."""
        return self._enqueue(_Line(next(self._numbers), line))

    def submit_command(
        self, command: Command, line: str | None = None, name: str | None = None
    ) -> int:
        """Queue a command a front end made (Space on a row of ``name``'s table), in
        turn with the typed lines; run as it is, never parsed."""
        return self._enqueue(_Line(next(self._numbers), line, command, name))

    def _enqueue(self, item: _Line) -> int:
        with self._lock:
            self._lines.append(item)
        self._pump()
        return item.seq

    def _pump(self) -> None:
        """Start the next lines while none runs: those the cell answers itself at once,
        then the first a target runs (the next waits for its Result)."""
        with self._lock:
            while self._running is None and self._lines:
                self._start(self._lines.popleft())

    def _route(self, item: _Line) -> Route:
        from ...commands.routing import Refused, route_command

        if item.command is None:
            return self.registry.plan(item.line or "", self.names, self.current)
        name = self.current if item.name is None else find_name(self.names, item.name)
        if name is None:
            from ...commands.cells import not_open

            return Refused(str(not_open(str(item.name), self.names)))
        text = item.line or ""
        return route_command(item.command, text, self.names, name, self.registry.traits)

    def _start(self, item: _Line) -> None:
        """Route one line and start it (under the lock)."""
        from ...commands.routing import Chained, OnEveryTarget, OnTarget, Refused, SwitchCurrent

        route = self._route(item)
        if isinstance(route, OnTarget | OnEveryTarget | SwitchCurrent):
            spec = self.registry.find(route.command)
            if spec is not None and not spec.runs_in(self.where):  # said once, not per target
                from ..commands.jobs import not_here

                text = not_here(self.registry, spec.name, self.where)
                self._answer(item, (Message(text, "error"),), route.command)
                return
        match route:
            case OnTarget(name=name, command=command):
                self.member(name).engine.submit_command(command, item.line, item.seq)
                self._running = item.seq
            case OnEveryTarget(command=command):
                self._to_every_target(item, command)
                self._running = item.seq
            case Chained():
                self._chain(item, route)
                self._running = item.seq
            case SwitchCurrent():
                self._use(item, route)
            case Refused(text=text):
                self._answer(item, (Message(text, "error"),))
            case _:  # a blank line, a comment
                self._answer(item, ())

    def _use(self, item: _Line, route: SwitchCurrent) -> None:
        member = self.member(route.name)
        self.current = member.name
        label = member.target.label
        shown = f"{member.name} ({terminal_safe(label)})" if label else member.name
        said = Message(f"current target: {shown}; @NAME runs a line elsewhere")
        self._answer(item, (said,), route.command)

    def _chain(self, item: _Line, route: Chained) -> None:
        """``wait ... after @FIRST ...``: FIRST's wait now, this target's once it held."""
        chain = _Chain(item.seq, item.line, route.command, route.first, route.second)
        first = self.member(route.first).engine
        self._chains[first.submit_command(route.first_wait)] = chain

    def _advance(self, chain: _Chain, result: Result) -> list[Result]:
        """A chained wait's job ended: the second wait starts, or the whole answer."""
        from ...commands.outcome import Outcome
        from ..published.events import Result
        from .chained_wait import chained_feedback, met

        outcome = next((f for f in result.feedback if isinstance(f, Outcome)), None)
        if chain.first_outcome is None:  # the first target's wait
            if outcome is None or not met(outcome):
                feedback = (
                    chained_feedback(chain.first, outcome, chain.second, None)
                    if outcome is not None
                    else result.feedback
                )
                return [Result(chain.seq, feedback, chain.line, chain.command)]
            chain.first_outcome = outcome
            second = replace(chain.command, after=None)
            self._chains[self.member(chain.second).engine.submit_command(second)] = chain
            return []
        feedback = (
            chained_feedback(chain.first, chain.first_outcome, chain.second, outcome)
            if outcome is not None
            else result.feedback
        )
        return [Result(chain.seq, feedback, chain.line, chain.command)]

    def _to_every_target(self, item: _Line, command: Command) -> None:
        """A line for the whole cell (``publish``): run by every target, answered once."""
        gather = _Gather(item.seq, item.line, command, {})
        for member in self.members:
            self._gathers[member.engine.submit_command(command)] = gather
            gather.waiting[member.name] = None

    def _gathered(self, name: str, gather: _Gather, result: Result) -> list[Result]:
        from ..published.events import Result

        gather.waiting[name] = result.feedback
        if any(feedback is None for feedback in gather.waiting.values()):
            return []
        feedback = tuple(f for each in gather.waiting.values() for f in each or ())
        return [Result(gather.seq, feedback, gather.line, gather.command)]

    def _answer(
        self, item: _Line, feedback: tuple[Feedback, ...], command: Command | None = None
    ) -> None:
        from ..published.events import Result

        self.outbox.put(Result(item.seq, feedback, item.line, command or item.command))

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
        from ..thread.engine import NOT_RUN

        dropped, self._dropped = self._dropped, []
        for item in dropped:
            self._answer(item, (Message(NOT_RUN, "error"),))

    def answer_confirm(self, seq: int, yes: bool) -> None:
        """The answer to a ConfirmWrite: its number names one job in the cell."""
        for member in self.members:
            member.engine.answer_confirm(seq, yes)

    def set_poll_frames(self, shown: bool) -> None:
        for member in self.members:
            member.engine.set_poll_frames(shown)

    def drain(self) -> list[tuple[str | None, Batch]]:
        """Everything published since the last drain: the cell's own results (None),
        then each target's batch, by name. The line running ends when its Result is
        here, and the next starts: so each drain holds the lines in the order typed."""
        drained: list[tuple[str | None, Batch]] = [(None, self.outbox.drain())]
        drained.extend((member.name, member.engine.outbox.drain()) for member in self.members)
        if not any(batch.events for _, batch in drained[1:]):
            return drained  # the first paint loads no event class
        from ..published.events import Result

        ended = False
        answers: list[Result] = []
        for name, batch in drained[1:]:
            if not batch.events:
                continue
            kept: list[Event] = []
            for event in batch.events:
                if not isinstance(event, Result):
                    kept.append(event)
                elif (chain := self._chains.pop(event.seq, None)) is not None:
                    answers.extend(self._advance(chain, event))
                elif (gather := self._gathers.pop(event.seq, None)) is not None:
                    answers.extend(self._gathered(str(name), gather, event))
                else:
                    kept.append(event)
                    ended = ended or event.seq == self._running
            batch.events[:] = kept
        drained[0][1].events.extend(answers)
        ended = ended or any(answer.seq == self._running for answer in answers)
        if ended:
            with self._lock:
                self._running = None
                self._say_dropped()
            self._pump()
        return drained
