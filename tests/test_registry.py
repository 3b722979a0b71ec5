"""A command is one registry entry: added here, in this file alone, it is listed by
``help``, completed, hinted, coloured, parsed and run by the console's engine, the
REPL and ``rac-console run`` alike; and several engines run side by side, one per
controller, sharing nothing.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from rac_console.cli.main import main
from rac_console.commands.language import VarRef, parse_var
from rac_console.engine import Engine, Feedback, Message
from rac_console.engine.commands.builtin import BUILTIN
from rac_console.engine.commands.context import JobContext
from rac_console.engine.commands.registry import EVERYWHERE, CommandSpec, Where, variable_completion
from rac_console.present.completion import complete, hint
from rac_console.present.tokens import tokenize
from rac_console.protocol import InputError
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import Driver, Front

pytestmark = pytest.mark.slow


@dataclass(frozen=True)
class Twice:
    """``twice TYPE INDEX``: read a variable twice and say whether it moved."""

    var: VarRef


def parse_twice(rest: str) -> Twice:
    var, after = parse_var(rest, "twice TYPE INDEX")
    if after.strip():
        raise InputError(f"twice takes one variable, not {after.strip()!r}")
    return Twice(var)


def run_twice(context: JobContext, command: Twice, line: str | None) -> list[Feedback]:
    controller = context.controller
    if controller is None:
        return [Message("not connected", "error")]
    first, second = (controller.get(command.var) for _ in range(2))
    if not (first.ok and second.ok):
        return [Message(f"{command.var} could not be read twice", "error")]
    moved = "moved" if first.variant != second.variant else "held still"
    return [Message(f"{command.var} {moved} between two reads")]


TWICE = CommandSpec(
    "twice",
    "TYPE INDEX",
    "read a variable twice: did it move?",
    parse_twice,
    run_twice,
    "twice I 1",
    where=EVERYWHERE,
    takes_variable=True,
    complete=variable_completion(),
    types=(Twice,),
)


@pytest.fixture
def registered() -> Iterator[CommandSpec]:
    BUILTIN.register(TWICE)
    try:
        yield TWICE
    finally:
        BUILTIN.unregister(TWICE.name)


def test_the_entry_gives_help_completion_hint_and_colour(registered: CommandSpec) -> None:
    assert "twice TYPE INDEX  -  read a variable twice: did it move?" in BUILTIN.help_lines("twice")
    assert any(line.startswith("twice TYPE INDEX") for line in BUILTIN.help_lines())
    assert [c.text for c in complete("tw")] == ["twice"]
    assert "IO" in [c.text for c in complete("twice ")]
    assert [c.text for c in complete("twice I ", seen=[("I", 7)])] == ["7"]
    assert hint("twice ") == "TYPE INDEX"
    assert hint("twice I ") == "INDEX"
    assert tokenize("twice I 1")[0] == ("command", "twice")


def test_the_console_engine_runs_it(registered: CommandSpec) -> None:
    engine = Engine(None, interval=0.05, timeout=1.0)
    engine.start()
    front = Front(engine)
    try:
        assert front.run("twice I 3") == ["I3 held still between two reads"]
        assert front.errors("twice I 3 I 4") == ["twice takes one variable, not 'I 4'"]
    finally:
        engine.stop()
    assert front.sent().count(b"GET:RC8:3:I:\r") == 2


async def test_the_repl_runs_it(registered: CommandSpec, tmp_path: Path) -> None:
    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type("twice I 3\r")
        await d.until(lambda out: "I3 held still between two reads" in out, "twice's answer")

    await driver.run(steps)


def test_run_runs_it_and_refuses_what_only_runs_at_a_terminal(
    registered: CommandSpec, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = tmp_path / "steps.txt"
    script.write_text("twice I 3\n", encoding="utf-8")
    assert main(["run", str(script)]) == 0
    said = capsys.readouterr()
    assert "I3 held still between two reads" in said.out

    BUILTIN.unregister(TWICE.name)
    BUILTIN.register(CommandSpec(**{**TWICE.__dict__, "where": frozenset({Where.CONSOLE})}))
    assert main(["run", str(script)]) == 2
    said = capsys.readouterr()
    assert "'twice' works in the console and the REPL" in said.err


def test_two_engines_poll_two_controllers_side_by_side() -> None:
    """One engine per controller: each polls its own, and a write to one is never
    seen by the other (they share no session, watch list or outbox)."""
    with SimulatorThread() as one, SimulatorThread() as two:
        engines = [Engine(sim.host, sim.port, interval=0.05, timeout=1.0) for sim in (one, two)]
        fronts = [Front(engine) for engine in engines]
        for engine in engines:
            engine.start()
        try:
            fronts[0].run("put I 20 111")
            fronts[1].run("put I 20 222")
            for front in fronts:
                front.run("watch I 20")
            for front, value in zip(fronts, (111, 222), strict=True):
                front.until(
                    lambda front=front, value=value: _shown(front, "I20") == value,  # type: ignore[misc]
                    f"I20 = {value}",
                )
            fronts[0].run("connect sim")  # one changes target: the other goes on
            before = len(fronts[1].sent())
            fronts[1].until(lambda: len(fronts[1].sent()) > before + 2, "the other still polls")
            assert fronts[1].status is not None and fronts[1].status.port == two.port
        finally:
            for engine in engines:
                engine.stop()


def _shown(front: Front, key: str) -> object:
    row = front.rows.get(key)
    return row.variant.value if row is not None and row.variant is not None else None
