"""A one-shot write without ``-H`` goes to a simulator started for that command alone,
which ends with it: a ``put`` then a ``get`` showed the old value with no word why
(issue 41). The write says so on stderr; its stdout and ``--json`` are what they are
on a simulator that stays. The real CLI as a subprocess."""

from __future__ import annotations

import json
import re

import pytest

from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import cli

#: Subprocesses: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

GONE = "rac-console: the write is gone when this command ends"


def said_gone(stderr: str) -> bool:
    return any(line.startswith(GONE) for line in stderr.splitlines())


@pytest.mark.parametrize(
    "words",
    [("put", "I", "10", "5"), ("send", "PUT:RC8:10:I:3,5"), ("--json", "put", "I", "10", "5")],
)
def test_a_write_to_its_own_simulator_says_it_is_gone(
    env: dict[str, str], words: tuple[str, ...]
) -> None:
    result = cli(env, *words)
    assert result.returncode == 0, result.stderr
    last = result.stderr.splitlines()[-1]
    assert last.startswith(GONE), result.stderr
    assert "rac-console sim and -H 127.0.0.1" in last and "run -" in last  # what to do instead
    then = cli(env, "get", "I", "10")
    assert then.stdout.startswith("I10 = 0 "), then.stdout  # as it says: the next one is fresh
    assert not said_gone(then.stderr)


@pytest.mark.parametrize(
    "words",
    [
        ("get", "I", "10"),
        ("send", "GET:RC8:10:I:"),
        ("put", "I", "10", "x"),  # refused: nothing was written
        ("--read-only", "put", "I", "10", "5"),
    ],
)
def test_nothing_written_nothing_said(env: dict[str, str], words: tuple[str, ...]) -> None:
    assert not said_gone(cli(env, *words).stderr)


def without_times(stdout: str) -> str:
    return re.sub(r"\d+(?:\.\d+)? ms", "<ms> ms", stdout)


def test_stdout_and_json_are_as_on_a_simulator_that_stays(env: dict[str, str]) -> None:
    """Only stderr says it: a script reading stdout sees nothing new."""
    for json_option in ((), ("--json",)):
        own = cli(env, *json_option, "put", "I", "10", "5")
        with SimulatorThread() as kept:
            there = cli(env, "-H", f"127.0.0.1:{kept.port}", *json_option, "put", "I", "10", "5")
        assert said_gone(own.stderr) and not said_gone(there.stderr)
        assert (own.returncode, there.returncode) == (0, 0)
        if json_option:
            ours, theirs = json.loads(own.stdout), json.loads(there.stdout)
            assert ours.pop("rtt_ms") >= 0 and theirs.pop("rtt_ms") >= 0
            assert ours == theirs
            assert own.stdout.count("\n") == 1
        else:
            assert without_times(own.stdout) == without_times(there.stdout)
            assert own.stdout.startswith("I10: 0 → 5  S_OK  read back 5 ✓")
