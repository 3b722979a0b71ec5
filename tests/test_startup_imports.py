"""A one-shot command against a controller starts lean: it loads no event loop, no TLS,
no simulator and no full-screen toolkit, which would only lengthen every ``get``.

What a user notices is the start-up time; what is checked here is its cause, the
modules loaded, so the test does not depend on the machine's speed.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.sim.thread import SimulatorThread

#: A subprocess each: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

#: Modules the one-shot path must not load when a host is given.
HEAVY = ("asyncio", "ssl", "rac_console.sim", "textual", "prompt_toolkit")

#: Each one-shot command, as words after ``-H HOST -p PORT`` ({script}: a file of lines).
ONE_SHOT_COMMANDS = {
    "get": ["get", "I", "1"],
    "get --json": ["--json", "get", "I", "1"],
    "put": ["put", "I", "1", "5"],
    "send": ["send", "GET:RC8:10:I:"],
    "run": ["run", "{script}"],
    "latency": ["latency", "3", "I", "1"],
}


@pytest.fixture(scope="module")
def simulator_port() -> Iterator[int]:
    """A simulator in this test process: the child process under test only connects."""
    with SimulatorThread() as simulator:
        yield simulator.port


def modules_loaded_by(words: list[str]) -> tuple[int, list[str]]:
    """Run ``main(words)`` in a fresh interpreter: its exit status and the heavy modules
    it loaded."""
    probe = (
        "import sys\n"
        "from rac_console.cli.main import main\n"
        f"status = main({words!r})\n"
        f"heavy = sorted(m for m in {HEAVY!r} if m in sys.modules)\n"
        "print('HEAVY', status, ','.join(heavy))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=30
    )
    assert result.returncode == 0, result.stderr
    marker, status, heavy = result.stdout.splitlines()[-1].split(" ")
    assert marker == "HEAVY", result.stdout
    return int(status), heavy.split(",") if heavy else []


@pytest.mark.parametrize("command", ONE_SHOT_COMMANDS)
def test_one_shot_against_a_host_loads_no_event_loop_tls_simulator_or_toolkit(
    command: str, simulator_port: int, tmp_path: Path
) -> None:
    script = tmp_path / "script.rac"
    script.write_text("get I 1\nput I 2 7\n", encoding="utf-8")
    words = [w.format(script=script) for w in ONE_SHOT_COMMANDS[command]]
    status, heavy = modules_loaded_by(["-H", "127.0.0.1", "-p", str(simulator_port), *words])
    assert status == 0
    assert heavy == [], f"{command} loaded {heavy}"


def test_version_loads_no_event_loop_tls_simulator_or_toolkit() -> None:
    probe = (
        "import sys\n"
        "from rac_console.cli.main import main\n"
        "try:\n"
        "    main(['--version'])\n"
        "except SystemExit:\n"
        "    pass\n"
        f"print('HEAVY', ','.join(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=30
    )
    assert result.stdout.splitlines()[-1] == "HEAVY ", result.stdout
