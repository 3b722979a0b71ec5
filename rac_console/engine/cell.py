"""A cell: one engine per controller behind one front end, and the lines routed to them.

The RAC spec wants one session per request in flight, so a cell is never one session
shared: each target has its own engine (its session, watch list, poller and rules, on
its own thread) and its own outbox. The cell routes each typed line: ``@NAME LINE`` to
that target, any other line to the current one (``use NAME`` changes it). A write thus
always goes to one controller, named by the line or by the prompt, under that
controller's own rules. Jobs are numbered by one counter for the whole cell, so a
number names one job whichever engine runs it.

The files are the cell's: one ``--record``, one ``--log`` transcript and one CSV log for
every target, each line naming its target (:class:`~.engine.CellFiles`). The members'
options name no file; the cell opens them before any thread starts, says a failure once
(it stops that file for every target), and closes them once every member has stopped.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from ..protocol import InputError
from ..protocol.text import endpoint, terminal_safe
from .engine import CellFiles, Engine
from .feedback import Message
from .options import EngineOptions
from .outbox import Batch, Outbox
from .where import Where

if TYPE_CHECKING:  # the console's first paint loads none of these
    from ..commands.language import Command, Use, Wait
    from ..commands.outcome import Outcome
    from ..commands.target import Target
    from .cellcsv import CellCsv
    from .events import Event, Feedback, Result
    from .frame_files import FrameFiles
    from .registry import Registry


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
            from .cellcsv import CellCsv
            from .frame_files import FrameFiles

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
                        else CellFiles(name, files.view(name), csv)
                    ),
                ),
            )
            for name, target in targets
        )
        self._by_name = {member.name: member for member in self.members}
        self.current = self.members[0].name
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
        cell._by_name = {member.name: member}
        cell.current = member.name
        cell._chains = {}
        cell._gathers = {}
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
        found = self._by_name.get(self.current if name is None else name)
        if found is None:
            from ..commands.cells import not_open

            raise not_open(str(name), self.names)
        return found

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
        from .events import Alert

        self.outbox.put(Alert(text))

    # ------------------------------------------------------------------ jobs

    def submit(self, line: str) -> int:
        """Queue a typed line on its target; its Result carries the number returned
        (from the target's outbox, or the cell's for ``use`` and a problem with the
        line's ``@NAME``)."""
        from ..commands.cells import route
        from ..commands.language import Connect, Use, Wait
        from ..commands.plant import Publish

        try:
            name, rest = route(line, self.names, self.current)
            member = self.member(name)
        except InputError as exc:
            return self._answer(line, Message(str(exc), "error"))
        try:
            command = self.registry.parse(rest)
        except InputError:
            # The target says why, in its turn: after the lines queued before this one.
            return member.engine.submit(rest)
        if isinstance(command, Use):
            if self.where not in self.registry.spec_of(command).where:
                return member.engine.submit_command(command, line)  # the engine says why
            return self._use(command, line)
        if isinstance(command, Connect) and len(self.members) > 1:
            return self._answer(line, Message(self._fixed(), "error"))
        if isinstance(command, Wait) and command.after is not None:
            return self._chain(command, member.name, line)
        if isinstance(command, Publish) and len(self.members) > 1 and rest == line:
            return self._to_every_target(command, line)
        if command is None:  # a blank line, a comment
            return member.engine.submit(rest)
        return member.engine.submit_command(command, line)

    def submit_command(
        self, command: Command, line: str | None = None, name: str | None = None
    ) -> int:
        """Queue a command a front end made (Space on a row of ``name``'s table)."""
        from ..commands.language import Connect, Use

        if isinstance(command, Use):
            return self._use(command, line)
        if isinstance(command, Connect) and len(self.members) > 1:
            return self._answer(line, Message(self._fixed(), "error"))
        return self.member(name).engine.submit_command(command, line)

    def _fixed(self) -> str:
        return (
            f"a cell's targets are fixed ({', '.join(self.names)}): use NAME picks one; "
            "to open others, start rac-console with -H a,b or --cell NAME"
        )

    def _use(self, command: Use, line: str | None) -> int:
        try:
            member = self.member(command.name)
        except InputError as exc:
            return self._answer(line, Message(str(exc), "error"))
        self.current = member.name
        label = member.target.label
        shown = f"{member.name} ({terminal_safe(label)})" if label else member.name
        return self._answer(line, Message(f"current target: {shown}; @NAME runs a line elsewhere"))

    def _chain(self, command: Wait, name: str, line: str | None) -> int:
        """``wait ... after @FIRST ...``: FIRST's wait now, this target's once it held."""
        after = command.after
        assert after is not None
        try:
            first = self.member(after.target)
        except InputError as exc:
            return self._answer(line, Message(str(exc), "error"))
        chain = _Chain(next(self._numbers), line, command, first.name, name)
        self._chains[first.engine.submit_command(after.wait)] = chain
        return chain.seq

    def _advance(self, chain: _Chain, result: Result) -> list[Result]:
        """A chained wait's job ended: the second wait starts, or the whole answer."""
        from ..commands.outcome import Outcome
        from .chained_wait import chained_feedback, met
        from .events import Result

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

    def _to_every_target(self, command: Command, line: str | None) -> int:
        """A line for the whole cell (``publish``): run by every target, answered once."""
        gather = _Gather(next(self._numbers), line, command, {})
        for member in self.members:
            self._gathers[member.engine.submit_command(command)] = gather
            gather.waiting[member.name] = None
        return gather.seq

    def _gathered(self, name: str, gather: _Gather, result: Result) -> list[Result]:
        from .events import Result

        gather.waiting[name] = result.feedback
        if any(feedback is None for feedback in gather.waiting.values()):
            return []
        feedback = tuple(f for each in gather.waiting.values() for f in each or ())
        return [Result(gather.seq, feedback, gather.line, gather.command)]

    def _answer(self, line: str | None, message: Message) -> int:
        from .events import Result

        seq = next(self._numbers)
        self.outbox.put(Result(seq, (message,), line))
        return seq

    def cancel(self, queued: bool = False) -> None:
        """Esc, Ctrl-C: every target's running job (and with ``queued`` those behind
        it) stops; next to moving machinery, stop means everywhere."""
        for member in self.members:
            member.engine.cancel(queued)

    def answer_confirm(self, seq: int, yes: bool) -> None:
        """The answer to a ConfirmWrite: its number names one job in the cell."""
        for member in self.members:
            member.engine.answer_confirm(seq, yes)

    def set_poll_frames(self, shown: bool) -> None:
        for member in self.members:
            member.engine.set_poll_frames(shown)

    def drain(self) -> list[tuple[str | None, Batch]]:
        """Everything published since the last drain: the cell's own results (None),
        then each target's batch, by name."""
        drained: list[tuple[str | None, Batch]] = [(None, self.outbox.drain())]
        drained.extend((member.name, member.engine.outbox.drain()) for member in self.members)
        if self._chains or self._gathers:  # steps of the cell's own, answered as one
            from .events import Result

            answers: list[Result] = []
            for name, batch in drained[1:]:
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
                batch.events[:] = kept
            drained[0][1].events.extend(answers)
        return drained
