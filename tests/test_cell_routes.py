"""A line's way through a cell (issue 43): planned once, carried out by the one executor
of routes (the console's cell and ``run`` give it only how a target runs a command), and
the cell's queue moving with no front end draining it.

The executor's own tests give it targets written here (inline, or answering when the
test says, as an engine answers on its thread); the cell's run against fake controllers
that record what they receive, judged from their side.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

from rac_console.commands.advice import COMMAND_LINE, Advice
from rac_console.commands.language import Command
from rac_console.commands.routing import Route
from rac_console.commands.target import Target
from rac_console.engine import Message, Result
from rac_console.engine.cell.cell import Cell
from rac_console.engine.cell.routes import Answer, Done, Line, Routes
from rac_console.engine.commands.builtin import BUILTIN
from rac_console.engine.commands.registry import Registry
from rac_console.engine.setup.options import EngineOptions
from rac_console.engine.setup.where import Where
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import (
    confirm_console,
    connected,
    declined_with_keys_typed_ahead,
    until,
)
from tests.support.servers import RecordingServer

Servers = Callable[..., RecordingServer]
MEMBERS = [("A", Target("127.0.0.1", 5006)), ("B", Target("127.0.0.1", 5007))]


class Inline:
    """Targets that run a command at once, as ``run``'s sessions do, and say which
    target ran which line."""

    def __init__(self) -> None:
        self.ran: list[tuple[str, str | None, bool]] = []

    def run(self, name: str, command: Command, line: Line, done: Done, whole: bool) -> None:
        self.ran.append((name, line.text, whole))
        done((Message(f"{name} ran it"),))


class Later:
    """Targets that answer when the test says, as an engine answers on its own thread."""

    def __init__(self) -> None:
        self.waiting: dict[str, Done] = {}

    def run(self, name: str, command: Command, line: Line, done: Done, whole: bool) -> None:
        self.waiting[name] = done


def routes_of(targets: Inline | Later, where: Where = Where.CONSOLE) -> Routes:
    return Routes(targets, MEMBERS, lambda: BUILTIN, where)


def test_the_executor_runs_a_line_on_its_target_and_use_moves_the_current_one() -> None:
    targets = Inline()
    routes = routes_of(targets)
    on_a = routes.answer(Line(1, "get I 1"))
    assert on_a.by == "A" and on_a.parts == (("A", (Message("A ran it"),)),)
    moved = routes.answer(Line(2, "use b"))  # names in any case
    assert routes.current == "B" and moved.by is None
    assert "current target: B" in str(moved.feedback)
    assert routes.answer(Line(3, "get I 1")).by == "B"
    refused = routes.answer(Line(4, "@Z put I 1 5"))
    assert refused.by is None and "no target named Z" in str(refused.feedback)
    assert targets.ran == [("A", "get I 1", True), ("B", "get I 1", True)]


def test_a_line_every_target_runs_is_answered_once_in_the_cells_order() -> None:
    targets = Later()
    routes = routes_of(targets)
    answers: list[Answer] = []
    line = Line(1, "publish off")
    routes.execute(routes.plan(line), line, answers.append)
    assert set(targets.waiting) == {"A", "B"} and answers == []
    targets.waiting["B"]((Message("B off"),))  # the second target answers first
    assert answers == []
    targets.waiting["A"]((Message("A off"),))
    [answer] = answers
    assert answer.parts == (("A", (Message("A off"),)), ("B", (Message("B off"),)))


def test_a_chained_wait_whose_first_wait_did_not_run_never_waits_on_the_second() -> None:
    targets = Later()
    routes = routes_of(targets)
    answers: list[Answer] = []
    line = Line(1, "@B wait IO 64 on within 1 after @A IO 128 on")
    routes.execute(routes.plan(line), line, answers.append)
    assert list(targets.waiting) == ["A"]
    targets.waiting.pop("A")((Message("A: not connected", "error"),))
    assert targets.waiting == {}
    [answer] = answers
    assert answer.feedback == (Message("A: not connected", "error"),)


def test_what_only_runs_at_a_terminal_is_refused_once_in_run_and_runs_nowhere() -> None:
    targets = Inline()
    answer = routes_of(targets, Where.RUN).answer(Line(1, "publish off"))
    [said] = answer.feedback
    assert isinstance(said, Message) and said.level == "error" and "'publish'" in said.text
    assert targets.ran == []


# ------------------------------------------------------------- the cell's queue


class Broken(Registry):
    """The built-in commands, with a bug in the planner for one line."""

    def plan(
        self, line: str, names: Sequence[str], current: str, advice: Advice = COMMAND_LINE
    ) -> Route:
        if line == "boom":
            raise RuntimeError("a bug")
        return super().plan(line, names, current, advice)


def test_a_bug_in_planning_a_line_answers_it_and_the_next_line_still_runs() -> None:
    cell = Cell(MEMBERS, registry=Broken(BUILTIN))  # never started: nothing is sent
    boom, use = cell.submit("boom"), cell.submit("use b")
    answers = {
        event.seq: str(event.feedback)
        for _, batch in cell.drain()
        for event in batch.events
        if isinstance(event, Result)
    }
    assert "internal error" in answers[boom] and "current target: B" in answers[use]


def reply(line: bytes) -> bytes:
    return b"0\r" if line.startswith(b"PUT:") else b"0,3,5\r"


@pytest.mark.slow
def test_a_cell_that_no_front_end_drains_still_runs_its_next_lines(recording: Servers) -> None:
    """A script, or a cell with no screen: each line runs once the one before it has
    ended, whether or not anything drains the outboxes."""
    a, b = recording(reply), recording(reply)
    targets = [("A", Target("127.0.0.1", a.port)), ("B", Target("127.0.0.1", b.port))]
    cell = Cell(targets, options=EngineOptions(timeout=2.0), where=Where.CONSOLE)
    cell.start()
    try:
        seqs = [cell.submit("@A get I 1"), cell.submit("@B get I 2"), cell.submit("get I 3")]
        cell.submit("@B get I 4")  # starts once the third line's answer is out
        assert b.wait_line(b"GET:RC8:2:I:"), "the second line never ran"
        assert a.wait_line(b"GET:RC8:3:I:"), "the third line never ran"
        assert b.wait_line(b"GET:RC8:4:I:"), "the fourth line never ran"
        # One drain now holds the first three answers, robotA's twice and robotB's
        # between them: they are read in the order the lines were submitted.
        read = [
            (name, event.seq)
            for name, batch in cell.drain()
            for event in batch.events
            if isinstance(event, Result) and event.seq in seqs
        ]
        assert read == [("A", seqs[0]), ("B", seqs[1]), ("A", seqs[2])]
    finally:
        cell.stop()


# ---------------------------------------------------------- planned once


@pytest.mark.slow
async def test_a_typed_write_is_planned_once_and_its_keys_typed_ahead_still_held(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The console's guard of the keys typed ahead of a write's question reads the
    route its cell planned the line to: the line is planned once, by the registry that
    runs it."""
    planned: list[str] = []
    plan = Registry.plan

    def counted(self: Registry, line: str, *args: object, **kwargs: object) -> object:
        planned.append(line)
        return plan(self, line, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Registry, "plan", counted)
    with SimulatorThread() as simulator:
        app = confirm_console(tmp_path, simulator)
        async with app.run_test(size=(100, 30)) as pilot:
            await connected(pilot, app)
            await declined_with_keys_typed_ahead(pilot, app)
            await until(pilot, lambda: not app.main_screen.lines.pending, "the answer")
            assert app.main_screen.panes.command_line.value == ""  # the y never got there
    assert planned.count("put IO 67 on") == 1
