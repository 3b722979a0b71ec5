"""A command, declared once: name, arguments, help, completion, hint, where it runs,
its parser and its handler.

Everything that knows about a command reads its entry: ``help``, completion, hints,
the lexer's colours, the parser, the job runner (:mod:`.jobs`) and ``run``'s refusal
of what only works at a terminal. Adding a command is one entry in a module of
:mod:`rac_console.engine.commands.builtin` and its word in the language's
:data:`~rac_console.commands.language.COMMAND_WORDS` (or :meth:`Registry.register` at
run time), and its tests; no front end matches on its name.

An entry is typed by the context its handler takes and the command object its parser
makes: a :class:`CommandSpec` runs with any job's context (:class:`~.context.JobContext`:
the console's, the REPL's, ``rac-console run``'s, the command line's), an
:class:`EngineSpec` with an engine's (:class:`~.context.CommandContext`). mypy checks
each entry where it is made: the handler takes what the parser makes and the context
its kind of entry gives.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, Generic, TypeVar

from ...commands.advice import COMMAND_LINE, Advice
from ...commands.exchange_parsers import parse_exchange
from ...commands.language import (
    Command,
    FrameFile,
    Simple,
    Step,
    WatchFile,
    is_raw_line,
    split_word,
)
from ...commands.line import check_length
from ...commands.routing import Route, Traits, plan
from ...protocol import KINDS, InputError
from ...protocol.text import close_match
from ..published.events import Feedback, Message

# Kept here too, where the commands' modules find them with the rest of a command's spec.
from ..setup.where import AT_A_TERMINAL as AT_A_TERMINAL
from ..setup.where import EVERYWHERE as EVERYWHERE
from ..setup.where import Where as Where
from ..setup.where import reaches
from .context import CommandContext, JobContext

#: (completion text, what it means)
Option = tuple[str, str]


@dataclass(frozen=True)
class Sources:
    """What completion may offer beyond the registry: indices used or watched (TYPE,
    index), and the config file's profiles (name, label or host)."""

    seen: Iterable[tuple[str, int]] = ()
    targets: Iterable[Option] = ()
    commands: Sequence[Option] = ()  # every command and its summary (help TOPIC)
    cell: Sequence[Option] = ()  # the open targets of a cell (use, @NAME), with their labels


#: The options for the argument being typed, given the arguments before it (``P 10``
#: already split as ``P``, ``10``).
Completer = Callable[[list[str], Sources], Sequence[Option]]
#: What the command still needs after the arguments given, in grey; "" for nothing.
Hinter = Callable[[list[str]], str]
#: The context a handler takes (:class:`~.context.JobContext` or
#: :class:`~.context.CommandContext`).
C = TypeVar("C")
#: The command object a parser makes and its handler runs.
T = TypeVar("T")
#: Runs the parsed command (``T``) on the engine's thread (or the CLI's), given its
#: job's context (``C``): the feedback to show, and the line typed (None: a command a
#: front end made, with nothing to echo).
Handler = Callable[[C, T, "str | None"], list[Feedback]]


TYPE_OPTIONS: tuple[Option, ...] = tuple((code, kind.title) for code, kind in KINDS.items())


def no_completion(args: list[str], sources: Sources) -> Sequence[Option]:
    return ()


def variable_completion(
    after: Callable[[str, list[str]], Sequence[Option]] | None = None,
    first: Sequence[Option] = (),
) -> Completer:
    """TYPE, then an index seen before, then (``after(type code, words after the
    index)``) what the command takes next. ``first`` adds options to the types."""

    def complete(args: list[str], sources: Sources) -> Sequence[Option]:
        if not args:
            return (*TYPE_OPTIONS, *first)
        kind = KINDS.get(args[0].upper())
        if kind is None:
            return ()
        if len(args) == 1:
            indices = sorted({i for code, i in sources.seen if code == kind.code})
            return [(str(i), f"{kind.code}{i}") for i in indices]
        return after(kind.code, args[2:]) if after is not None else ()

    return complete


def no_argument(step: Step) -> Callable[[str], Simple]:
    """The parser of a command that takes nothing."""

    def parse(rest: str) -> Simple:
        if rest:
            raise InputError(f"{step.value} takes no argument")
        return Simple(step)

    return parse


def words_of(arguments: str) -> Hinter:
    """The default hint: the usage's words not yet given, one per argument typed."""
    needs = arguments.split()

    def hint(args: list[str]) -> str:
        return " ".join(needs[len(args) :])

    return hint


@dataclass(frozen=True)
class Spec(Generic[C, T]):
    """What every entry holds; made as a :class:`CommandSpec` or an :class:`EngineSpec`,
    which say the context its handler takes."""

    name: str
    arguments: str
    summary: str
    parse: Callable[[str], T]
    handle: Handler[C, T]
    example: str = ""
    notes: tuple[str, ...] = ()  # more lines for ``help NAME``
    where: frozenset[Where] = AT_A_TERMINAL
    takes_variable: bool = False  # TYPE INDEX first: coloured, and P10 split as P 10
    complete: Completer = no_completion
    hint: Hinter | None = None  # None: the usage's words (:func:`words_of`)
    #: The command objects its parser makes (one at least): the registry finds the
    #: entry of a command a front end made by them, and the handler is given only them.
    types: tuple[type[T], ...] = field(default=())
    #: What the planner and the guards know of it: whether it writes, where it runs in
    #: a cell (:mod:`rac_console.commands.routing`). Its handler's context is declared
    #: with it (:meth:`run`): the write gate refuses every write of a command declared
    #: never to write (the default).
    traits: Traits = field(default_factory=Traits)

    @property
    def usage(self) -> str:
        return f"{self.name} {self.arguments}".strip()

    def hint_for(self, args: list[str]) -> str:
        return (self.hint or words_of(self.arguments))(args)

    def runs_in(self, where: Where) -> bool:
        """Whether it runs ``where``: a place it declares, and in a served console only
        when it reaches nothing but its target (no file, no other host)."""
        return where in self.where and reaches(where, self.traits.reaches)

    def command_of(self, command: object) -> T:
        """``command`` as its handler takes it (TypeError: this entry does not run it)."""
        if isinstance(command, self.types):
            return command
        raise TypeError(f"{self.name} does not run {type(command).__name__}")


@dataclass(frozen=True)
class CommandSpec(Spec[JobContext, T]):
    """A command whose handler takes any job's context: it runs wherever :attr:`where`
    says, ``rac-console run`` and the command line included."""

    def run(self, context: JobContext, command: object, line: str | None) -> list[Feedback]:
        declared = context.declaring(self.name, self.traits.writes)
        return self.handle(declared, self.command_of(command), line)


@dataclass(frozen=True)
class EngineSpec(Spec[CommandContext, T]):
    """A command whose handler takes an engine's context (the watch list, the files,
    the target): the console's, the REPL's, the command line's ``watch``."""

    def run(self, context: JobContext, command: object, line: str | None) -> list[Feedback]:
        engine = context.engine_context()
        if engine is None:  # its ``where`` says a place with no engine: a mistake
            return [Message(f"{self.name!r} needs the console or the REPL", "error")]
        declared = engine.declaring(self.name, self.traits.writes)
        return self.handle(declared, self.command_of(command), line)


#: An entry of any command: each entry's own command type is checked where it is made,
#: and :meth:`Spec.command_of` checks a command against it before its handler runs.
AnySpec = CommandSpec[Any] | EngineSpec[Any]


#: Words typed for a command that has another name here (suggested, never run).
_MEANT = {"exit": "quit", "q": "quit", ":q": "quit", "bye": "quit", "?": "help", "h": "help"}


def _named(command: Command) -> str | None:
    """The name of a command whose object is shared by several entries (pause and
    resume are one :class:`Simple`; record and transcript one :class:`FrameFile`)."""
    if isinstance(command, Simple):
        return command.step.value
    if isinstance(command, FrameFile):
        return command.kind
    if isinstance(command, WatchFile):
        return command.action
    return None


RAW_HELP = "GET:... / PUT:... lines are sent exactly as typed (raw RAC entry)"


class Registry:
    """The commands by name, in the order ``help`` lists them, and the handler of each
    kind of command object (a raw line, or F2's pause, made without a name)."""

    def __init__(self, specs: Iterable[AnySpec] = ()) -> None:
        self._specs: dict[str, AnySpec] = {}
        self._by_type: dict[type, AnySpec] = {}
        for spec in specs:
            self.register(spec)

    def register(self, spec: AnySpec) -> AnySpec:
        """Add ``spec`` (after the others: ``help`` lists it last)."""
        if not spec.types:
            raise ValueError(f"{spec.name}: its entry names no command type (types=...)")
        self._specs[spec.name] = spec
        for kind in spec.types:
            self._by_type.setdefault(kind, spec)
        return spec

    def unregister(self, name: str) -> None:
        spec = self._specs.pop(name)
        self._by_type = {k: s for k, s in self._by_type.items() if s is not spec}

    def __iter__(self) -> Iterator[AnySpec]:
        return iter(list(self._specs.values()))

    def __contains__(self, name: object) -> bool:
        return name in self._specs

    def get(self, name: str) -> AnySpec | None:
        return self._specs.get(name)

    def names(self) -> list[str]:
        return list(self._specs)

    def find(self, command: Command) -> AnySpec | None:
        """The entry that runs ``command`` (a command object carries no name); None when
        none does."""
        named = _named(command)
        return self._specs.get(named) if named is not None else self._by_type.get(type(command))

    def spec_of(self, command: Command) -> AnySpec:
        """The entry that runs ``command``; LookupError when none does."""
        spec = self.find(command)
        if spec is None:
            raise LookupError(f"no command runs {type(command).__name__}")
        return spec

    def parse(self, line: str) -> Command | None:
        """One line of the command language; None for a blank line or a ``#`` comment."""
        check_length(line)
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            return None
        if is_raw_line(line):
            return parse_exchange(line.rstrip("\r\n"))
        word, rest = split_word(line.rstrip("\r\n"))
        spec = self._specs.get(word)
        if spec is None:
            meant = _MEANT.get(word.lower()) or close_match(word, self._specs)
            meant = meant if meant in self._specs else None
            guess = f"did you mean {meant}? " if meant is not None else ""
            raise InputError(
                f"unknown command {word!r}: {guess}type help for the list, "
                "or start a raw line with GET: or PUT:"
            )
        command: Command = spec.parse(rest)  # or an object of a command registered at run time
        return command

    def help_lines(self, topic: str | None = None) -> list[str]:
        """The text of ``help`` or ``help COMMAND``."""
        if topic:
            spec = self._specs.get(topic.lower())
            if spec is None:
                return [f"no command {topic!r}: type help for the list"]
            lines = [f"{spec.usage}  -  {spec.summary}"]
            if spec.example:
                lines.append(f"  e.g. {spec.example}")
            lines.extend(f"  {note}" for note in spec.notes)
            return lines
        specs = list(self._specs.values())
        width = max(len(s.usage) for s in specs)
        return [f"{s.usage:<{width}}  {s.summary}" for s in specs] + [RAW_HELP]

    def traits(self, command: Command) -> Traits:
        """What ``command``'s entry declares of it (a command no entry runs: a target's)."""
        spec = self.find(command)
        return spec.traits if spec is not None else Traits()

    def plan(
        self, line: str, names: Sequence[str], current: str, advice: Advice = COMMAND_LINE
    ) -> Route:
        """The route of a typed line in a cell of ``names`` (see :func:`...routing.plan`)."""
        return plan(line, names, current, self.parse, self.traits, advice)

    def runs_in(self, where: Where) -> list[str]:
        return [spec.name for spec in self._specs.values() if spec.runs_in(where)]


def in_order(specs: Iterable[AnySpec], words: Sequence[str]) -> list[AnySpec]:
    """``specs`` in the order of ``words`` (the language's command words, as ``help``
    lists them). ValueError naming every entry whose word is not there, every word
    with no entry and every word given twice: a command added is listed where it is
    declared, or the registry does not load."""
    by_name: dict[str, AnySpec] = {}
    twice = [word for n, word in enumerate(words) if word in words[:n]]
    for spec in specs:
        if spec.name in by_name:
            twice.append(spec.name)
        by_name[spec.name] = spec
    unplaced = [name for name in by_name if name not in words]
    missing = [word for word in words if word not in by_name]
    problems = [
        f"{what}: {', '.join(names)}"
        for what, names in (
            ("not among the command words (commands/language.py: COMMAND_WORDS)", unplaced),
            ("command words with no entry", missing),
            ("declared twice", twice),
        )
        if names
    ]
    if problems:
        raise ValueError("the built-in commands: " + "; ".join(problems))
    return [by_name[word] for word in words]
