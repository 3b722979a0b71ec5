"""The console's start: what it loads before its first paint, and that starting lean
changes nothing it shows or parses.

The first paint waits for every module loaded before it, so what it loads is checked
here (the cause), never how long it takes (the machine's speed).
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rac_console.cli.main import parse_args
from rac_console.cli.parser import build_cli
from rac_console.commands.policy import TargetProfile, WritePolicy, Writes
from rac_console.commands.target import Target
from rac_console.engine import Engine, EngineOptions, Status
from rac_console.engine.setup.where import Where

#: What the first screen does not need: the engine's parts and commands, the sessions,
#: the command language, the simulator, the help and the confirm question, TOML.
NOT_BEFORE_THE_FIRST_PAINT = (
    "rac_console.commands.language",
    "rac_console.commands.outcome",
    "rac_console.engine.commands.builtin",
    "rac_console.engine.published.events",
    "rac_console.engine.polling.link",
    "rac_console.engine.polling.poller",
    "rac_console.engine.commands.registry",
    "rac_console.session.blocking",
    "rac_console.sim",
    "rac_console.tui.confirm_screen",
    "rac_console.tui.help_screen",
    "tomllib",
)

DEADLINE = 20.0

#: The console as ``rac-console`` starts it, told to write the modules it has loaded
#: to a file once its first screen is painted, and to end there.
PROBE = """
import os, sys
import rac_console.cli.main as cli

def painted():
    with open(os.environ["PROBE_OUT"], "w", encoding="utf-8") as out:
        out.write("\\n".join(sorted(sys.modules)))
    os._exit(0)

cli._after_first_paint = painted
sys.exit(cli.main([]))
"""


@pytest.mark.slow
def test_the_first_paint_loads_no_engine_part_session_language_or_simulator(
    tmp_path: Path,
) -> None:
    pty = pytest.importorskip("pty")
    from tests.support.drivers import read_until, stop

    out = tmp_path / "modules"
    env = os.environ | {
        "HOME": str(tmp_path),
        "XDG_STATE_HOME": str(tmp_path),
        "XDG_CONFIG_HOME": str(tmp_path),
        "TERM": "xterm-256color",
        "PROBE_OUT": str(out),
    }
    master, slave = pty.openpty()
    process = subprocess.Popen(
        [sys.executable, "-c", PROBE], stdin=slave, stdout=slave, stderr=slave, env=env
    )
    os.close(slave)
    try:
        seen = read_until(master, lambda _: process.poll() is not None, DEADLINE)
    finally:
        stop(process)
        os.close(master)
    assert b"SIMULATOR" in seen, seen[-2000:]  # the first screen names its target
    assert out.exists(), seen[-2000:]
    loaded = set(out.read_text(encoding="utf-8").split("\n"))
    assert "rac_console.tui.app" in loaded
    early = sorted(
        name
        for name in loaded
        for heavy in NOT_BEFORE_THE_FIRST_PAINT
        if name == heavy or name.startswith(heavy + ".")
    )
    assert early == []


def started_status(engine: Engine) -> Status:
    """The status an engine publishes before it starts (the console's first screen)."""
    engine.publish_target()
    status = engine.outbox.drain().status
    assert status is not None
    return status


@pytest.mark.parametrize(
    "target",
    [
        Target(None, 5006),
        Target(None, 5006, read_only=True, read_only_flag=True),
        Target(
            "10.0.0.5",
            5007,
            TargetProfile("cell3", "10.0.0.5", 5007, "Cell 3", "red", WritePolicy(Writes.CONFIRM)),
            WritePolicy(Writes.CONFIRM),
        ),
    ],
)
def test_an_engine_says_the_same_first_status_before_its_parts_are_made(target: Target) -> None:
    options = EngineOptions(timeout=1.5, interval=0.25, verify=False, cycles=True)
    lean = Engine(target=target, options=options, where=Where.CONSOLE)
    made = Engine(target=target, options=options, where=Where.CONSOLE)
    made.set_poll_frames(True)  # makes its parts (as a start does), opens nothing
    assert started_status(lean) == started_status(made)


def test_the_console_with_no_words_parses_as_the_whole_grammar_would() -> None:
    assert vars(parse_args([])) == vars(build_cli().parser.parse_args([]))


@pytest.mark.parametrize(
    "package", ["rac_console.protocol", "rac_console.session", "rac_console.engine"]
)
def test_every_name_a_package_exports_loads_from_its_module(package: str) -> None:
    module = importlib.import_module(package)
    for name in module.__all__:
        value = getattr(module, name)
        assert value is not None, name
    with pytest.raises(AttributeError):
        module.no_such_name  # noqa: B018
