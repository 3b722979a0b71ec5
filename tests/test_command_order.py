"""The built-in commands: each declared once, listed in one declared order, each entry
run only with the context and the command object its handler takes.

``help`` lists the commands in the order of the language's ``COMMAND_WORDS``. Every
entry of every module of ``rac_console.engine.commands.builtin`` is there exactly once; an
entry added without its word (or a word without its entry) stops the registry from
loading, rather than being listed wherever its module happened to put it.
"""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import rac_console.engine.commands.builtin as package
from rac_console.commands.exchange_parsers import parse_get
from rac_console.commands.language import COMMAND_WORDS, Get, Simple, Step
from rac_console.engine import Feedback, Message
from rac_console.engine.commands.builtin import BUILTIN, help_lines, parse_command
from rac_console.engine.commands.context import JobContext
from rac_console.engine.commands.jobs import run_job
from rac_console.engine.commands.registry import (
    EVERYWHERE,
    AnySpec,
    CommandSpec,
    EngineSpec,
    Registry,
    Where,
    in_order,
)
from rac_console.engine.commands.session_context import SessionContext
from rac_console.engine.setup.options import target_of


def module_specs() -> dict[str, list[AnySpec]]:
    """Each module's entries, read from the modules themselves (not the registry)."""
    found: dict[str, list[AnySpec]] = {}
    for info in pkgutil.iter_modules(package.__path__):
        module = importlib.import_module(f"{package.__name__}.{info.name}")
        found[info.name] = list(module.SPECS)
    return found


def read_twice(context: JobContext, command: Get, line: str | None) -> list[Feedback]:
    return [Message(f"{command.var} twice")]


def entry(name: str) -> AnySpec:
    return CommandSpec(name, "TYPE INDEX", "read twice", parse_get, read_twice, types=(Get,))


def test_help_lists_the_commands_in_the_declared_order() -> None:
    assert BUILTIN.names() == list(COMMAND_WORDS)
    listed = [line.split()[0] for line in help_lines()[:-1]]  # the last: raw lines
    assert listed == list(COMMAND_WORDS)


def test_every_entry_of_every_module_is_declared_once() -> None:
    specs = module_specs()
    assert {"connection", "exchanges", "frames", "publishing", "watching"} <= set(specs)
    names = [spec.name for entries in specs.values() for spec in entries]
    assert sorted(names) == sorted(COMMAND_WORDS)
    assert len(set(COMMAND_WORDS)) == len(COMMAND_WORDS)
    for entries in specs.values():
        for spec in entries:
            assert BUILTIN.get(spec.name) is spec


def test_an_entry_without_its_word_stops_the_registry_loading() -> None:
    with pytest.raises(ValueError, match=r"not among the command words .*: twice"):
        in_order([*BUILTIN, entry("twice")], COMMAND_WORDS)


def test_a_word_without_its_entry_or_twice_stops_it_too() -> None:
    with pytest.raises(ValueError, match=r"command words with no entry: twice"):
        in_order(list(BUILTIN), (*COMMAND_WORDS, "twice"))
    with pytest.raises(ValueError, match=r"declared twice: get, get"):
        get = BUILTIN.get("get")
        assert get is not None
        in_order([*BUILTIN, get], (*COMMAND_WORDS, "get"))


def test_the_order_is_the_words_not_the_modules() -> None:
    reversed_words = tuple(reversed(COMMAND_WORDS))
    assert [spec.name for spec in in_order(BUILTIN, reversed_words)] == list(reversed_words)


def test_an_entry_names_the_command_objects_its_handler_takes() -> None:
    no_types = CommandSpec("twice", "TYPE INDEX", "read twice", parse_get, read_twice)
    with pytest.raises(ValueError, match="twice: its entry names no command type"):
        Registry([no_types])
    get = BUILTIN.get("get")
    assert get is not None
    with pytest.raises(TypeError, match="get does not run Simple"):
        get.command_of(Simple(Step.CLEAR))


def test_the_engine_commands_and_the_job_commands() -> None:
    """What runs in ``rac-console run`` takes a job's context; the rest an engine's."""
    job_commands = {spec.name for spec in BUILTIN if isinstance(spec, CommandSpec)}
    assert set(BUILTIN.runs_in(Where.RUN)) <= job_commands
    assert {"get", "put", "send", "latency", "wait", "use"} <= job_commands
    assert {"watch", "log", "connect", "record", "publish", "help"}.isdisjoint(job_commands)
    assert all(isinstance(spec, CommandSpec | EngineSpec) for spec in BUILTIN)


def test_an_engine_command_on_a_plain_session_is_refused_not_run() -> None:
    rules, _ = target_of(None, 5006, None, {})
    context = SessionContext(None, rules)  # type: ignore[arg-type]  # no session: never used
    watch = BUILTIN.get("watch")
    assert isinstance(watch, EngineSpec)
    said = watch.run(context, parse_command("watch I 1"), "watch I 1")
    assert said == [Message("'watch' needs the console or the REPL", "error")]
    # where it is asked of run, its place says so first
    _, said = run_job(BUILTIN, context, "watch I 1", Where.RUN)
    takes = ", ".join(BUILTIN.runs_in(Where.RUN))
    assert [m.text for m in said if isinstance(m, Message)] == [
        f"'watch' works in the console and the REPL; run takes {takes} and GET:/PUT: lines"
    ]


def test_a_job_command_registered_at_run_time_is_listed_last() -> None:
    registry = Registry(BUILTIN)
    registry.register(CommandSpec(**{**entry("twice").__dict__, "where": EVERYWHERE}))
    assert registry.names()[-1] == "twice"
    assert registry.names()[:-1] == list(COMMAND_WORDS)
