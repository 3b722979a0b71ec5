"""Target profiles from the real CLI, run as a subprocess: ``-H NAME`` uses the config
file's ``[target.NAME]``; a broken config file is one line and exit 2, never a traceback.

The config file is named by RAC_CONSOLE_CONFIG; the targets are a simulator and a
recording server in this process, on 127.0.0.1 port 0.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import cli, one_error_line, profile
from tests.support.servers import RecordingServer, unused_port

#: Subprocesses: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow


@pytest.fixture
def sim() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


def test_h_name_uses_the_profile(
    env: dict[str, str],
    config: Callable[[str], Path],
    sim: SimulatorThread,
) -> None:
    config(profile("cell3", sim.port, 'label = "Cell 3 — welding"\ncolour = "red"'))
    result = cli(env, "-H", "cell3", "get", "I", "1", "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["request"] == "GET:RC8:1:I:"
    assert "simulator" not in result.stderr  # the profile's host, not the built-in one


def test_an_explicit_port_overrides_the_profiles(
    env: dict[str, str],
    config: Callable[[str], Path],
    sim: SimulatorThread,
) -> None:
    config(profile("cell3", unused_port()))
    result = cli(env, "-H", "cell3", "-p", str(sim.port), "get", "I", "1")
    assert result.returncode == 0, result.stderr
    assert cli(env, "-H", "cell3", "get", "I", "1").returncode == 3  # its own port: nobody


def test_a_read_only_profile_refuses_writes_before_the_wire(
    env: dict[str, str],
    config: Callable[[str], Path],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording()
    config(profile("cell3", server.port, 'writes = "read-only"'))
    for words in (["put", "I", "1", "5"], ["send", "PUT:RC8:1:I:3,5"]):
        result = cli(env, "-H", "cell3", *words)
        assert result.returncode == 2, result.stderr
        assert "read-only" in one_error_line(result)
    script = cli(env, "-H", "cell3", "run", "--keep-going", "-", stdin="put I 1 5\nget I 10\n")
    assert script.returncode == 2
    assert bytes(server.received) == b"GET:RC8:10:I:\r"


def test_read_only_on_top_of_an_open_profile(
    env: dict[str, str],
    config: Callable[[str], Path],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording()
    config(profile("cell3", server.port))
    result = cli(env, "-H", "cell3", "--read-only", "put", "I", "1", "5")
    assert result.returncode == 2
    assert "read-only" in one_error_line(result)
    assert bytes(server.received) == b""


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ('[target.cell3]\nhost = "h"\nport = \n', "not valid TOML: Invalid value (at line 3"),
        ('[target.cell3]\nhost = "h"\nwrites = "maybe"\n', "[target.cell3] writes = 'maybe'"),
        ('[target.cell3]\nhost = "h"\ncolour = "light red"\n', "[target.cell3] colour"),
        ('[target.cell3]\nlabel = "x"\n', "[target.cell3] has no host"),
    ],
    ids=["syntax", "writes", "colour", "no host"],
)
@pytest.mark.parametrize(
    "words",
    [
        ["get", "I", "1"],
        ["-H", "cell3", "put", "I", "1", "5", "--json"],
        ["run", "-"],
        ["latency", "--count", "1"],
        ["watch", "I", "1", "--count", "1"],
        ["repl"],
        [],
    ],
    ids=lambda words: " ".join(words) or "console",
)
def test_a_broken_config_is_one_line_and_exit_2(
    env: dict[str, str],
    config: Callable[[str], Path],
    text: str,
    says: str,
    words: list[str],
) -> None:
    path = config(text)
    result = cli(env, *words, stdin="get I 1\n")
    assert result.returncode == 2, (result.stdout, result.stderr)
    line = one_error_line(result)
    assert line.startswith(f"rac-console: {path}: ") or line.startswith(f"rac-console: {path} ")
    assert says in line
    assert result.stdout == ""


def test_the_simulator_server_does_not_need_the_config(
    env: dict[str, str],
    config: Callable[[str], Path],
) -> None:
    config("not toml at all [")
    result = cli(env, "sim", "--help")
    assert result.returncode == 0, result.stderr


def test_a_missing_config_is_fine(env: dict[str, str], tmp_path: Path) -> None:
    env["XDG_CONFIG_HOME"] = str(tmp_path / "nowhere")  # no config.toml at the default path
    result = cli(env, "get", "I", "1", "--json")
    assert result.returncode == 0, result.stderr


def test_a_bare_name_that_is_no_profile_says_so_when_it_cannot_connect(
    env: dict[str, str],
    config: Callable[[str], Path],
) -> None:
    path = config(profile("cell3", unused_port()))
    result = cli(env, "-H", "cell4", "--timeout", "1", "get", "I", "1")
    assert result.returncode == 3
    assert f"no profile named cell4 in {path}" in one_error_line(result)
    result = cli(env, "-H", "127.0.0.1", "-p", str(unused_port()), "get", "I", "1")
    assert result.returncode == 3
    assert "no profile" not in result.stderr  # an address is no misspelt profile
