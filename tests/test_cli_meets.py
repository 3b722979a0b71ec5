"""Where the command line meets the rest: ``-H HOST:PORT`` for one target, refusals
that say what was meant, and the cell's targets named one by one (``watch @robotA``,
``check`` and ``latency`` on each). The real CLI as a subprocess; what a controller
received is judged at the fake controller."""

from __future__ import annotations

import json
from collections.abc import Callable

import pytest

from tests.support.drivers import cli, one_error_line
from tests.support.servers import RecordingServer


def test_host_and_port_in_one_word_reach_that_port(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording()
    result = cli(env, "-H", f"127.0.0.1:{server.port}", "--json", "get", "I", "1")
    assert result.returncode == 0, result.stderr
    assert server.lines == [b"GET:RC8:1:I:"]
    checked = cli(env, "-H", f"127.0.0.1:{server.port}", "check")
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert f"127.0.0.1:{server.port}" in checked.stdout and ":5006" not in checked.stdout


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (("gte", "I", "1"), "unknown command 'gte': did you mean get?"),
        (("wach", "I", "1"), "did you mean watch?"),
        (("watch", "I", "1", "--cout", "3"), "no option --cout: did you mean --count?"),
        (
            ("--count", "3", "watch", "I", "1"),
            "--count goes after watch: rac-console watch I 1 --count 3",
        ),
        (("--every=0.1", "watch", "I", "1"), "--every=0.1 goes after watch"),
        (("zzzz",), "the commands are get, put"),
    ],
)
def test_a_mistyped_command_line_is_one_line_saying_what_was_meant(
    env: dict[str, str], args: tuple[str, ...], says: str
) -> None:
    result = cli(env, *args)
    assert result.returncode == 2
    line = one_error_line(result)
    assert says in line, line
    assert "--help" in line and result.stdout == ""


@pytest.mark.parametrize(
    ("before", "after", "says"),
    [
        (("--hots", "127.0.0.1"), ("get", "I", "1"), "did you mean --host?"),
        (("--intreval", "0.2"), ("get", "I", "1"), "did you mean --interval?"),
        (("--intreval", "0.2"), ("watch", "I", "1"), "did you mean --interval?"),
        (("--hots", "127.0.0.1"), (), "did you mean --host?"),  # the console
    ],
)
def test_an_option_mistyped_before_the_command_is_named_as_after_it(
    env: dict[str, str], before: tuple[str, ...], after: tuple[str, ...], says: str
) -> None:
    """Not its value taken for the command (``unknown command '127.0.0.1'``)."""
    result = cli(env, *before, *after)
    assert result.returncode == 2
    line = one_error_line(result)
    assert f"no option {before[0]}: {says}" in line, line
    assert "unknown command" not in line and result.stdout == ""
    if after:  # the same typo after the command is met by the same guess
        behind = cli(env, *after, *before)
        assert behind.returncode == 2
        assert says in one_error_line(behind)


def test_a_cells_targets_are_watched_each_with_its_own_variables(env: dict[str, str]) -> None:
    result = cli(
        env, "--cell", "demo", "--json", "watch", "IO", "64", "@robotA", "IO", "128",
        "@ROBOTB", "I", "10", "--count", "1",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    lines = {line["target"]: line["values"] for line in map(json.loads, result.stdout.splitlines())}
    assert set(lines["robotA"]) == {"IO64", "IO128"}
    assert set(lines["robotB"]) == {"IO64", "I10"}
    only = cli(env, "--cell", "demo", "--json", "watch", "@robotA", "IO", "128", "--count", "1")
    assert only.returncode == 0, only.stderr
    assert [json.loads(line)["target"] for line in only.stdout.splitlines()] == ["robotA"]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (("--cell", "demo", "watch", "@robotC", "IO", "1"), "no target named robotC"),
        (("watch", "@robotA", "IO", "128"), "names a target of a cell"),
        (("--cell", "demo", "watch", "@robotA"), "missing variable"),
    ],
)
def test_a_target_named_in_a_watch_that_is_not_there_is_refused(
    env: dict[str, str], args: tuple[str, ...], says: str
) -> None:
    result = cli(env, *args, "--count", "1")
    assert result.returncode == 2
    assert says in result.stderr.splitlines()[-1]
    assert result.stdout == ""


@pytest.mark.parametrize("command", ["latency", "check"])
def test_check_and_latency_on_a_cell_measure_each_target(env: dict[str, str], command: str) -> None:
    extra = ("--count", "3") if command == "latency" else ()
    result = cli(env, "--cell", "demo", "--json", command, *extra)
    assert result.returncode == 0, result.stderr
    assert [json.loads(line)["target"] for line in result.stdout.split("\n") if line] == [
        "robotA",
        "robotB",
    ]
    text = cli(env, "--cell", "demo", command, *extra)
    assert text.returncode == 0, text.stderr
    assert text.stdout.startswith("robotA:\n") and "\nrobotB:\n" in text.stdout


def test_a_refused_write_is_never_ticked_though_the_value_read_back_matches(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    """IO 0 is an input: the controller refuses the PUT, and the bit happens to be ON,
    the value written. No ✓: the value read back is not the write's."""

    def reply(line: bytes) -> bytes:
        return b"-2147024891\r" if line.startswith(b"PUT") else b"0,11,-1\r"

    server = recording(reply)
    result = cli(env, *server.args, "put", "IO", "0", "on")
    assert result.returncode == 1
    assert "E_ACCESSDENIED" in result.stderr and "read back ON" in result.stderr
    assert "✓" not in result.stderr + result.stdout
    assert "the PUT was refused" in result.stderr
    as_json = cli(env, *server.args, "--json", "put", "IO", "0", "on")
    assert json.loads(as_json.stdout)["verified"] is False


@pytest.mark.parametrize("command", [("get", "I", "1"), ("watch", "I", "1", "--count", "1")])
def test_a_connection_that_fails_points_to_check(
    env: dict[str, str], command: tuple[str, ...]
) -> None:
    import socket

    with socket.socket() as unused:  # a port nothing listens on
        unused.bind(("127.0.0.1", 0))
        port = unused.getsockname()[1]
    result = cli(env, "-H", "127.0.0.1", "-p", str(port), *command)
    assert result.returncode == 3
    assert f"(rac-console check -H 127.0.0.1 -p {port} says why)" in result.stderr
