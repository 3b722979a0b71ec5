"""One executor of routes: what a planned line does on the targets, for every caller.

The planner (:mod:`rac_console.commands.routing`) says where a line goes; :class:`Routes`
plans it (once) and turns that route into work, in the one ``match`` there is: run it on
one target, on every target and answer once, wait on one target and then another, make
another target the current one, or answer itself (a refusal, nothing). Its callers differ
in one thing only, how a target runs a command, and that is its one parameter, a
:class:`Targets`:

- the console's, the REPL's and a served console's cell (:class:`~.cell.Cell`): each
  target's engine runs the command as a job, on its own thread, and the answer comes
  later, on that thread;
- ``rac-console run`` (:mod:`rac_console.cli.oneshot`): each target's session runs it
  inline, and the answer is in before :meth:`Routes.execute` returns
  (:meth:`Routes.answer` says so);
- the library's cell (``rac.cell(...)``, :mod:`rac_console.library.cell`): a line of
  ``cell.run("@robotA put I 10 5")`` goes through :meth:`Routes.answer` too, its
  :class:`Targets` running a command on the target's connection.

Its modules load when the first line is planned: a cell is made before the console's
first paint, which must not wait for the command language.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from ...commands.advice import COMMAND_LINE, Advice
from ...protocol.text import terminal_safe
from ..published.feedback import Message

if TYPE_CHECKING:
    from ...commands.language import Command
    from ...commands.routing import Chained, Route
    from ...commands.target import Target
    from ..commands.registry import Registry
    from ..published.events import Feedback
    from ..setup.where import Where

#: Called with a command's feedback once it has ended.
Done = Callable[[tuple["Feedback", ...]], None]


@dataclass(frozen=True)
class Line:
    """A line handed to :meth:`Routes.execute`: its number (a cell's job number, a
    script's line number), how it is shown, and the command a front end made for it
    (None: typed, planned from the text) with the target it is for (None: the current
    one)."""

    seq: int
    text: str | None
    command: Command | None = None
    name: str | None = None


@dataclass(frozen=True)
class Answer:
    """What a line came to: each target's feedback in the cell's order (None: the
    executor's own words, such as a refusal or ``use``'s)."""

    line: Line
    command: Command | None
    parts: tuple[tuple[str | None, tuple[Feedback, ...]], ...] = ()
    #: The one target that ran the line and whose feedback is its whole answer
    #: (:class:`Targets` was told ``whole``): a cell's engine has published it already.
    by: str | None = None

    @property
    def feedback(self) -> tuple[Feedback, ...]:
        """Every part's feedback, in order: a cell says the line's answer once."""
        return tuple(each for _, feedback in self.parts for each in feedback)


class Targets(Protocol):
    """How a caller's targets run a command: the executor's one parameter."""

    def run(self, name: str, command: Command, line: Line, done: Done, whole: bool) -> None:
        """Run ``command`` on the target ``name`` and call ``done`` once with its
        feedback when it has ended: before returning (a session run inline) or later,
        on any thread (an engine's job). ``whole``: that feedback is the line's whole
        answer (one target ran it), numbered ``line.seq``; else it is one step of an
        answer the executor makes (a chained wait, a line every target runs)."""


class Routes:
    """A cell's lines (one target is a cell of one), planned and carried out; the
    current target, which lines without ``@NAME`` go to (``use`` changes it).

    A caller hands it one line at a time, and the next once the last has answered (the
    cell's queue, ``run``'s loop): the executor keeps no queue of its own.
    """

    def __init__(
        self,
        targets: Targets,
        members: Sequence[tuple[str, Target]],
        registry: Callable[[], Registry],
        where: Where,
        advice: Advice = COMMAND_LINE,
    ) -> None:
        """``registry``: the commands the lines are planned and checked with, asked for
        when the first line comes; ``where``: where the lines run (what only works at a
        terminal is refused in ``run``, said once for the line, not once a target);
        ``advice``: the front end's words for what a refusal says to do instead."""
        self.targets = targets
        self.names = tuple(name for name, _ in members)
        self._labels = {name: target.label for name, target in members}
        self._registry = registry
        self.where = where
        self.advice = advice
        self.current = self.names[0]

    @property
    def registry(self) -> Registry:
        return self._registry()

    def plan(self, line: Line) -> Route:
        """The route of a typed line, or of the command a front end made for the target
        ``line.name`` (None: the current one): the one plan a line gets."""
        from ...commands.routing import Refused, route_command

        registry = self.registry
        if line.command is None:
            return registry.plan(line.text or "", self.names, self.current, self.advice)
        from ...commands.names import find_name

        name = self.current if line.name is None else find_name(self.names, line.name)
        if name is None:
            from ...commands.cells import not_open

            return Refused(str(not_open(str(line.name), self.names)))
        return route_command(
            line.command, line.text or "", self.names, name, registry.traits, advice=self.advice
        )

    def execute(self, route: Route, line: Line, finish: Callable[[Answer], None]) -> None:
        """Do what ``route`` says, then call ``finish`` once with the line's answer: at
        once (the executor answers it itself, or the targets run inline) or later, on a
        target's thread."""
        from ...commands.routing import (
            Chained,
            OnEveryTarget,
            OnTarget,
            Refused,
            SwitchCurrent,
        )

        not_here = self._not_here(route, line)
        if not_here is not None:
            finish(not_here)
            return
        match route:
            case OnTarget(name=name, command=command):

                def answered(feedback: tuple[Feedback, ...]) -> None:
                    finish(Answer(line, command, ((name, feedback),), by=name))

                self.targets.run(name, command, line, answered, whole=True)
            case OnEveryTarget(command=command):
                self._every_target(command, line, finish)
            case Chained():
                self._chained(route, line, finish)
            case SwitchCurrent(name=name, command=command):
                self.current = name
                label = self._labels.get(name)
                shown = f"{name} ({terminal_safe(label)})" if label else name
                said = f"current target: {shown}; @NAME runs a line elsewhere"
                finish(Answer(line, command, ((name, (Message(said),)),)))
            case Refused(text=text):
                finish(Answer(line, line.command, ((None, (Message(text, "error"),)),)))
            case _:  # a blank line, a comment
                finish(Answer(line, line.command))

    def answer(self, line: Line) -> Answer:
        """Plan and carry out a line whose targets run inline (``run``, a script's
        cell): its answer, in before this returns."""
        answers: list[Answer] = []
        self.execute(self.plan(line), line, answers.append)
        if not answers:
            raise RuntimeError("Routes.answer needs targets that run a command inline")
        return answers[0]

    # ------------------------------------------------------------------ the routes

    def _not_here(self, route: Route, line: Line) -> Answer | None:
        """The answer to a command that does not run where the lines run (``watch`` in
        ``run``), said once for the line rather than once a target; None when it runs."""
        from ...commands.routing import OnEveryTarget, OnTarget, SwitchCurrent
        from ..commands.jobs import not_here

        if not isinstance(route, OnTarget | OnEveryTarget | SwitchCurrent):
            return None
        spec = self.registry.find(route.command)
        if spec is None or spec.runs_in(self.where):
            return None
        said = Message(not_here(self.registry, spec.name, self.where), "error")
        return Answer(line, route.command, ((None, (said,)),))

    def _every_target(self, command: Command, line: Line, finish: Callable[[Answer], None]) -> None:
        """A line for the whole cell (``publish``): run by every target, answered once
        every target's feedback is in, in the cell's order."""
        lock = threading.Lock()
        parts: dict[str, tuple[Feedback, ...]] = {}

        def part_of(name: str) -> Done:
            def one_in(feedback: tuple[Feedback, ...]) -> None:
                with lock:  # each target's engine answers on its own thread
                    parts[name] = feedback
                    if len(parts) < len(self.names):
                        return
                finish(Answer(line, command, tuple((n, parts[n]) for n in self.names)))

            return one_in

        for name in self.names:
            self.targets.run(name, command, line, part_of(name), whole=False)

    def _chained(self, route: Chained, line: Line, finish: Callable[[Answer], None]) -> None:
        """``wait ... after @FIRST ...``: FIRST's wait, then (once it held) this
        target's; answered once, naming both (:mod:`.chained_wait`)."""
        from ...commands.outcome import Outcome
        from .chained_wait import chained_feedback, met

        def outcome_of(feedback: tuple[Feedback, ...]) -> Outcome | None:
            return next((f for f in feedback if isinstance(f, Outcome)), None)

        def said(feedback: tuple[Feedback, ...]) -> None:
            finish(Answer(line, route.command, ((None, feedback),)))

        def first_done(feedback: tuple[Feedback, ...]) -> None:
            first = outcome_of(feedback)
            if first is None:
                said(feedback)
            elif not met(first):
                said(chained_feedback(route.first, first, route.second, None))
            else:

                def second_done(feedback: tuple[Feedback, ...]) -> None:
                    second = outcome_of(feedback)
                    if second is None:
                        said(feedback)
                    else:
                        said(chained_feedback(route.first, first, route.second, second))

                self.targets.run(route.second, route.second_wait, line, second_done, whole=False)

        self.targets.run(route.first, route.first_wait, line, first_done, whole=False)
