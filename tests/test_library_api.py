"""The library's public face: the names ``rac_console`` exports (held here exactly), the
types a script's checker sees (``mypy --strict`` on a script that uses every name), the
``py.typed`` marker shipped, and the command line's start that loads none of it."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import rac_console as rac
from tests.support.doc_samples import run_python

ROOT = Path(__file__).resolve().parent.parent

PUBLIC = {
    "Cell",
    "Connection",
    "ConnectionFailed",
    "ControllerError",
    "OutcomeUnknown",
    "RacError",
    "ReadBackMismatch",
    "Reading",
    "Refused",
    "Sent",
    "Timeout",
    "UnknownTarget",
    "UnreadableReply",
    "Value",
    "Written",
    "aio",
    "cell",
    "connect",
}
AIO = {"AsyncCell", "AsyncConnection", "cell", "connect"}

#: A user's script: every public name, as a script would use it.
SCRIPT = """
from __future__ import annotations

import asyncio

import rac_console as rac
from rac_console import aio


def ask(variable: str, now: rac.Value | None, value: rac.Value) -> bool:
    return variable == "I10" and now != value


def main() -> None:
    rc: rac.Connection
    with rac.connect("sim", port=None, timeout=2.0, read_only=False, confirm=ask) as rc:
        count: int = rc.get("I", 10)
        ratio: float = rc.get("f", 1)
        text: str = rc.get("S", 1)
        bit: bool = rc.get("IO", 1)
        where: tuple[float, ...] = rc.get("P", 0)
        anything: rac.Value = rc.get("i".upper(), 1)
        written: rac.Written = rc.put("I", 10, count + 1)
        ok: bool | None = written.verified
        sent: rac.Sent = rc.send("GET:RC8:10:I:")
        code: int = sent.result
        for reading in rc.watch("I 10", "IO 128", every=0.2):
            seen: rac.Reading = reading
            print(seen.name, seen.value, seen.ok, seen.time, seen.error)
            break
        print(ratio, text, bit, where, anything, ok, code, rc.host, rc.port, rc.writes)
    cell: rac.Cell
    with rac.cell("demo", yes=True) as cell:
        robot: rac.Connection = cell["robotA"]
        try:
            cell["robotC"]
        except rac.UnknownTarget as unknown:
            print(unknown)
        result: rac.Value | rac.Written | rac.Sent | None = cell.run("@robotB get I 1")
        print(robot.profile, result, cell.names, cell.current)
    try:
        rac.connect("127.0.0.1", port=1)
    except rac.ConnectionFailed as failed:
        print(failed.hint, failed.problem)
    except rac.Refused as refused:
        print(refused)
    except rac.ControllerError as error:
        print(error.code, error.name, error.written)
    except rac.OutcomeUnknown as unknown:
        print(unknown.written)
    except rac.ReadBackMismatch as mismatch:
        print(mismatch.written.read_back)
    except rac.Timeout as timeout:
        print(timeout)
    except rac.UnreadableReply as unreadable:
        print(unreadable.raw)
    except rac.RacError as other:
        print(other)


async def awaited() -> None:
    async with aio.connect("sim") as rc:
        first, second = await asyncio.gather(rc.get("I", 1), rc.get("I", 2))
        total: int = first + second
        written: rac.Written = await rc.put("D", 1, 0.5)
        sent: rac.Sent = await rc.send("GET:RC8:1:I:")
        async for reading in rc.watch("I 1", every=0.1):
            print(reading.value)
            break
        print(total, written, sent)
    opened: aio.AsyncConnection = await rac.aio.connect("sim")
    await opened.close()
    async with aio.cell("demo") as cell:
        typed: aio.AsyncCell = cell
        print(await typed.run("get I 1"))


main()
asyncio.run(awaited())
"""


def test_the_public_names_are_exactly_these() -> None:
    assert set(rac.__all__) == PUBLIC and len(rac.__all__) == len(PUBLIC)
    for name in rac.__all__:
        assert getattr(rac, name) is not None, name
    assert set(rac.aio.__all__) == AIO
    assert issubclass(rac.Timeout, TimeoutError) and issubclass(
        rac.ConnectionFailed, ConnectionError
    )
    assert issubclass(rac.UnknownTarget, KeyError)
    for error in (
        "Refused",
        "ControllerError",
        "OutcomeUnknown",
        "ConnectionFailed",
        "Timeout",
        "UnknownTarget",
        "UnreadableReply",
    ):
        assert issubclass(getattr(rac, error), rac.RacError), error
    with pytest.raises(AttributeError, match="no attribute 'conect'"):
        rac.conect  # noqa: B018


def test_py_typed_ships_in_the_wheel() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert "py.typed" in config["tool"]["setuptools"]["package-data"]["rac_console"]
    assert (ROOT / "rac_console" / "py.typed").is_file()


def test_the_command_line_loads_none_of_the_library() -> None:
    probe = (
        "import sys, contextlib, io\n"
        "from rac_console.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        main(['--help'])\n    except SystemExit:\n        pass\n"
        "import rac_console\n"
        "print(sorted(m for m in sys.modules if m.startswith(('rac_console.library', "
        "'rac_console.aio'))))\n"
        "rac_console.connect\n"
        "print('rac_console.library.connection' in sys.modules)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=60, check=True
    )
    assert done.stdout.splitlines() == ["[]", "True"]


@pytest.mark.slow
def test_a_script_that_uses_every_public_name_type_checks_strictly(tmp_path: Path) -> None:
    script = tmp_path / "script.py"
    script.write_text(SCRIPT, encoding="utf-8")
    env = dict(os.environ, MYPYPATH=str(ROOT))
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "mypy",
            "--strict",
            "--follow-imports=silent",
            "--cache-dir",
            str(tmp_path / "cache"),
            str(script),
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.slow
def test_the_script_runs_against_the_simulator(tmp_path: Path, env: dict[str, str]) -> None:
    done = run_python(SCRIPT, tmp_path, env)
    assert done.returncode == 0, done.stderr
    assert "nothing accepts connections" in done.stdout
