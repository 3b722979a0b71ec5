"""A refusal says what to do instead in the words of the front end that refused: a script
is told what to pass to ``rac.connect`` or ``rac.cell``, the command line what to type.
Each case once through the library and once through the CLI, nothing sent in either."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

import rac_console as rac
from tests.support.drivers import cli, one_error_line, profile
from tests.support.servers import Memory, RecordingServer

#: (what is refused, the script's call, the command line's arguments and stdin).
CASES: list[tuple[str, str, tuple[str, ...], str]] = [
    ("a confirm target's write", "put", ("-H", "cell3", "put", "I", "10", "5"), ""),
    ("sim in a cell", "cell sim", ("-H", "sim,cell3", "get", "I", "1"), ""),
    ("a cell that is not there", "cell nowhere", ("--cell", "nowhere", "get", "I", "1"), ""),
    ("an IPv6 address unclosed", "connect [::1", ("-H", "[::1", "get", "I", "1"), ""),
    ("another target in a cell", "in a cell", ("--cell", "demo", "run", "-"), "connect x\n"),
]

#: What each says to do, in a script and on the command line.
SAID = {
    "a confirm target's write": (
        "pass yes=True or confirm=a function to rac.connect (or rac.cell) to write "
        "(nothing was sent)",
        "add --yes to write from a script or the command line (nothing was sent)",
    ),
    "sim in a cell": ('sim is not one (try rac.cell("demo"))', "sim is not one (try --cell demo)"),
    "a cell that is not there": ('or try rac.cell("demo")', "or try --cell demo"),
    "an IPv6 address unclosed": (
        'write an IPv6 address in brackets: "[::1]" or "[::1]:5006"',
        "write an IPv6 address in brackets: connect [::1] or [::1]:5006",
    ),
    "another target in a cell": (
        "to open others, open them with rac.connect(...) or rac.cell([...])",
        "to open others, start rac-console with -H a,b or --cell NAME",
    ),
}


def _confirm_config(tmp_path: Path, server: RecordingServer) -> Path:
    path = tmp_path / "config.toml"
    path.write_text(profile("cell3", server.port, 'writes = "confirm"'), encoding="utf-8")
    return path


def _script_call(call: str, config: Path) -> Callable[[], object]:
    def put() -> None:
        with rac.connect("cell3", config=config) as rc:
            rc.put("I", 10, 5)

    def in_a_cell() -> None:
        with rac.cell("demo") as cell:
            cell.run("connect x")

    return {
        "put": put,
        "cell sim": lambda: rac.cell(["sim", "cell3"], config=config),
        "cell nowhere": lambda: rac.cell("nowhere", config=config),
        "connect [::1": lambda: rac.connect("[::1", config=config),
        "in a cell": in_a_cell,
    }[call]


@pytest.mark.parametrize(("case", "call", "args", "stdin"), CASES, ids=[c[0] for c in CASES])
def test_a_script_is_told_what_to_pass(
    case: str, call: str, args: tuple[str, ...], stdin: str, recording, tmp_path: Path
) -> None:
    server = recording(Memory())
    with pytest.raises(rac.Refused) as refused:
        _script_call(call, _confirm_config(tmp_path, server))()
    said = str(refused.value)
    assert SAID[case][0] in said
    assert "--" not in said and "rac-console" not in said
    assert server.lines == []


@pytest.mark.slow
@pytest.mark.parametrize(("case", "call", "args", "stdin"), CASES, ids=[c[0] for c in CASES])
def test_the_command_line_is_told_what_to_type(
    case: str,
    call: str,
    args: tuple[str, ...],
    stdin: str,
    recording,
    tmp_path: Path,
    env: dict[str, str],
) -> None:
    server = recording(Memory())
    config = _confirm_config(tmp_path, server)
    done = cli(env | {"RAC_CONSOLE_CONFIG": str(config)}, *args, stdin=stdin)
    assert done.returncode == 2, done.stderr
    said = done.stderr if stdin else one_error_line(done)
    assert SAID[case][1] in said
    assert server.lines == []
