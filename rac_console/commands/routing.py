"""Which controller a line goes to, decided in one place: the planner.

Every front end hands a typed line to :func:`plan` (the console and the REPL through
the cell, ``run`` line by line, the one-shot CLI with its ``@NAME`` word) and gets a
route back: this target or another named one, every target, the cell itself (``use``),
a chained wait, or a refusal that says why. What the planner needs to know of a command
is declared on its spec as :class:`Traits` (whether it writes, its scope), never
guessed from its type by the front ends. Pure: no socket, no thread.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from enum import Enum

from ..protocol import InputError
from .advice import COMMAND_LINE, Advice
from .cells import not_open, split_address
from .language import Command, Raw, Use, Wait
from .names import find_name
from .reach import Reach as Reach  # declared there, for the config file's keys too


class Scope(Enum):
    """Where a command runs in a cell."""

    TARGET = "target"  # one target: the current one, or the one @NAME names
    CELL = "cell"  # the cell answers it itself, no target runs it (use)
    EVERY_TARGET = "every target"  # without @NAME every target runs it (publish)
    ONE_TARGET = "one target"  # changes the target (connect): refused in a cell of several


class WriteTrait(Enum):
    """Whether a command writes to the controller."""

    NEVER = "never"
    ALWAYS = "always"  # put
    UNLESS_GET = "unless a well-formed GET"  # a raw line, send


@dataclass(frozen=True)
class Traits:
    """What the planner and the guards know of a command, declared on its spec."""

    writes: WriteTrait = WriteTrait.NEVER
    scope: Scope = Scope.TARGET
    reaches: Reach = Reach.TARGET

    def writes_with(self, command: Command) -> bool:
        """Whether ``command`` (one of this spec's) may write: a put, a raw line but a
        well-formed GET."""
        if self.writes is WriteTrait.UNLESS_GET:
            return not (isinstance(command, Raw) and command.request.read_only_safe)
        return self.writes is WriteTrait.ALWAYS


@dataclass(frozen=True)
class OnTarget:
    """Run ``command`` on the target ``name``; ``text`` is the line without its @NAME."""

    name: str
    command: Command
    text: str
    writes: bool = False


@dataclass(frozen=True)
class OnEveryTarget:
    """Run ``command`` on every target of the cell, answered once."""

    command: Command


@dataclass(frozen=True)
class SwitchCurrent:
    """``use NAME``: the cell's current target becomes ``name`` (an open target's name)."""

    name: str
    command: Command


@dataclass(frozen=True)
class Chained:
    """``wait ... after @FIRST ...``: FIRST's wait, then (once it held) this target's."""

    first: str
    first_wait: Wait
    second: str
    second_wait: Wait
    command: Wait  # the wait as typed, both conditions


@dataclass(frozen=True)
class Nothing:
    """A blank line or a comment: nothing runs."""


@dataclass(frozen=True)
class Refused:
    """The line goes nowhere: why, and how to write it."""

    text: str


Route = OnTarget | OnEveryTarget | SwitchCurrent | Chained | Nothing | Refused


def plan(
    line: str,
    names: Sequence[str],
    current: str,
    parse: Callable[[str], Command | None],
    traits: Callable[[Command], Traits],
    advice: Advice = COMMAND_LINE,
) -> Route:
    """The route of a typed line in a cell whose targets are ``names`` (one target is a
    cell of one), ``current`` taking the lines without ``@NAME``. ``parse`` reads a line
    of the command language (None: blank, a comment); ``traits`` tells a command's;
    ``advice`` is the front end's words for what a refusal says to do instead."""
    try:
        named, text = split_address(line)
        name = current if named is None else find_name(names, named)
        if name is None:
            return Refused(str(not_open(str(named), names)))
        command = parse(text)
    except InputError as exc:
        return Refused(str(exc))
    if command is None:
        return Nothing()
    return route_command(
        command, text, names, name, traits, addressed=named is not None, advice=advice
    )


def route_command(
    command: Command,
    text: str,
    names: Sequence[str],
    name: str,
    traits: Callable[[Command], Traits],
    *,
    addressed: bool = True,
    advice: Advice = COMMAND_LINE,
) -> Route:
    """The route of a command made or parsed already, for the target ``name``
    (``addressed``: the line named it with ``@NAME``)."""
    trait = traits(command)
    several = len(names) > 1
    match trait.scope:
        case Scope.CELL:
            assert isinstance(command, Use)  # the one command the cell answers itself
            found = find_name(names, command.name)
            if found is None:
                return Refused(str(not_open(command.name, names)))
            return SwitchCurrent(found, command)
        case Scope.ONE_TARGET if several:
            return Refused(
                f"a cell's targets are fixed ({', '.join(names)}): use NAME picks one; "
                f"to open others, {advice.other_targets}"
            )
        case Scope.EVERY_TARGET if several and not addressed:
            return OnEveryTarget(command)
    if isinstance(command, Wait) and command.after is not None:
        first = find_name(names, command.after.target)
        if first is None:
            return Refused(str(not_open(command.after.target, names)))
        return Chained(first, command.after.wait, name, replace(command, after=None), command)
    return OnTarget(name, command, text, trait.writes_with(command))
