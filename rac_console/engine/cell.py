"""A cell: one engine per controller behind one front end, and the lines routed to them.

The RAC spec wants one session per request in flight, so a cell is never one session
shared: each target has its own engine (its session, watch list, poller and rules, on
its own thread) and its own outbox. The cell routes each typed line: ``@NAME LINE`` to
that target, any other line to the current one (``use NAME`` changes it). A write thus
always goes to one controller, named by the line or by the prompt, under that
controller's own rules. Jobs are numbered by one counter for the whole cell, so a
number names one job whichever engine runs it.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

from ..commands.cells import split_address
from ..commands.language import Command, Connect, Use
from ..commands.target import Target
from ..protocol import InputError
from ..protocol.text import terminal_safe
from .commands import BUILTIN
from .engine import Engine, EngineOptions
from .events import Message, Result
from .outbox import Batch, Outbox
from .registry import Registry, Where


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
    host = f"[{target.host}]" if ":" in target.host else target.host
    return f"{host}:{target.port}"


class Cell:
    """Start it, submit lines (``@NAME`` or the current target), drain, stop it."""

    def __init__(
        self,
        targets: Sequence[tuple[str, Target]],
        *,
        options: EngineOptions | None = None,
        notify: Callable[[], None] | None = None,
        where: Where = Where.CONSOLE,
        registry: Registry = BUILTIN,
    ) -> None:
        """One engine per ``(name, target)``, in order; the first is the current one.
        Raises InputError when a file cannot be opened (before any thread starts)."""
        if not targets:
            raise InputError("a cell needs at least one target")
        numbers = itertools.count(1)
        members = [
            Member(
                name,
                target,
                Engine(
                    target=target,
                    options=options,
                    outbox=Outbox(notify),
                    where=where,
                    registry=registry,
                    numbers=numbers,
                ),
            )
            for name, target in targets
        ]
        self._setup(members, numbers, notify, where, registry)

    @classmethod
    def of(cls, engine: Engine, name: str | None = None) -> Cell:
        """A cell of one member around an engine already made (a front end given an
        engine): the cell's own answers are numbered by the engine's counter."""
        cell = cls.__new__(cls)
        target = engine.target
        member = Member(name or member_name(target), target, engine)
        cell._setup([member], engine.numbers, engine.outbox.notify, engine.where, engine.registry)
        return cell

    def _setup(
        self,
        members: Sequence[Member],
        numbers: Iterator[int],
        notify: Callable[[], None] | None,
        where: Where,
        registry: Registry,
    ) -> None:
        self.registry, self.where = registry, where
        self._numbers = numbers
        #: The cell's own results (``use``, a line for a target it does not have).
        self.outbox = Outbox(notify)
        self.members: tuple[Member, ...] = tuple(members)
        self._by_name = {member.name: member for member in self.members}
        self.current = self.members[0].name

    @property
    def outboxes(self) -> tuple[Outbox, ...]:
        """The cell's own outbox, then each member's: a front end sets their notify."""
        return (self.outbox, *(member.engine.outbox for member in self.members))

    # ------------------------------------------------------------------ members

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(member.name for member in self.members)

    def member(self, name: str | None = None) -> Member:
        """The target named ``name`` (None: the current one); InputError naming the
        open targets when there is none by that name."""
        found = self._by_name.get(self.current if name is None else name)
        if found is None:
            raise InputError(
                f"no target named {terminal_safe(str(name))} is open here; "
                f"open: {', '.join(self.names)}"
            )
        return found

    def start(self, connect: bool = True) -> None:
        for member in self.members:
            member.engine.start(connect)

    def stop(self, timeout: float = 5.0) -> None:
        for member in self.members:
            member.engine.stop(timeout)

    # ------------------------------------------------------------------ jobs

    def submit(self, line: str) -> int:
        """Queue a typed line on its target; its Result carries the number returned
        (from the target's outbox, or the cell's for ``use`` and a problem with the
        line's ``@NAME``)."""
        try:
            name, rest = split_address(line)
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
        if command is None:
            return member.engine.submit(rest)
        return member.engine.submit_command(command, line)

    def submit_command(
        self, command: Command, line: str | None = None, name: str | None = None
    ) -> int:
        """Queue a command a front end made (Space on a row of ``name``'s table)."""
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

    def _answer(self, line: str | None, message: Message) -> int:
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
        return drained
