"""Issue 19, item 3: controller strings in the CSV log (``log FILE.csv``, ``watch
--log-csv``) are neutralised, never obeyed. A text cell starting like a formula
(``=``, ``+``, ``-``, ``@``, TAB, CR) is prefixed with ``'`` and quoted (OWASP, CSV
injection); ESC, BEL and every other control character are escaped as ``\\xNN``, as
the screen and the transcript show them; an LF or a CR in a value never splits a row.
Numbers are left alone: an I of -5 is ``-5``.

Against the real simulator where it can hold the value (it refuses control
characters, as a controller's PUT would), and against a server written here that
answers with them (a controller the simulator cannot be).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.commands.language import VarRef
from rac_console.engine import Engine
from rac_console.engine.watch.csvlog import CsvLog
from rac_console.protocol import VT, Variant, kind_of
from rac_console.session.blocking import Session
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import Front, cli
from tests.support.servers import RecordingServer

#: What the simulator is given (put as typed), and how each cell must read back.
FORMULAS = {
    "S10": ('=HYPERLINK("x")', '\'=HYPERLINK("x")'),
    "S11": ("+cmd|' /C calc'!A0", "'+cmd|' /C calc'!A0"),
    "S12": ("@SUM(1)", "'@SUM(1)"),
    "S13": ("-2+3", "'-2+3"),
    "S14": ("a=b, plain", "a=b, plain"),
}
#: Numbers stay numbers, whatever sign they start with.
NUMBERS = {"I10": ("-5", "-5"), "F10": ("-1.5e3", "-1500"), "D10": ("+2.5", "2.5")}

#: A controller string made to attack: a retitle (OSC 0), a clipboard write (OSC 52),
#: a bell, an LF to split the row, a TAB; and a formula at the start.
HOSTILE = '=HYPERLINK("x")\x1b]0;pwned\x07\x1b]52;c;ZXZpbA==\x07a\nb\tc'
HOSTILE_CELL = '\'=HYPERLINK("x")\\x1b]0;pwned\\x07\\x1b]52;c;ZXZpbA==\\x07a\\x0ab\\x09c'


def hostile_controller(line: bytes) -> bytes:
    """S answers HOSTILE, I answers -5, anything else 0 (I4)."""
    if line.endswith(b":S:"):
        return b"0,8," + HOSTILE.encode("ascii") + b"\r"
    if line.endswith(b":I:"):
        return b"0,3,-5\r"
    return b"0,3,0\r"


def parsed(data: bytes) -> list[list[str]]:
    return list(csv.reader(io.StringIO(data.decode("utf-8"), newline="")))


def assert_one_row_per_line(data: bytes, width: int) -> list[list[str]]:
    """The file a user opens: no ESC, no BEL, no stray CR or LF; each line one row."""
    assert b"\x1b" not in data and b"\x07" not in data, data
    assert data.endswith(b"\r\n"), data
    lines = data[:-2].split(b"\r\n")
    assert b"\n" not in data.replace(b"\r\n", b"") and b"\r" not in data.replace(b"\r\n", b"")
    rows = parsed(data)
    assert len(rows) == len(lines), data  # line count == header + rows
    assert [parsed(line + b"\r\n")[0] for line in lines] == rows  # each line parses alone
    assert all(len(row) == width for row in rows), rows
    return rows


def by_column(rows: list[list[str]]) -> list[dict[str, str]]:
    header, *values = rows
    return [dict(zip(header, row, strict=True)) for row in values]


def put_as_typed(host: str, port: int, values: dict[str, tuple[str, str]]) -> None:
    """Each value written to the simulator as ``put`` would write it."""
    with Session(host, port, timeout=5) as session:
        for name, (typed, _) in values.items():
            kind = kind_of(name[0])
            reply = session.put(kind, int(name[1:]), kind.value_from_text(typed))
            assert reply.response.ok, (name, reply)


# ----------------------------------------------------------- the console: log FILE


@pytest.fixture
def front() -> Iterator[Front]:
    engine = Engine(None, interval=0.02, timeout=1.0)
    engine.start()
    try:
        yield Front(engine)
    finally:
        engine.stop()


def test_the_console_log_prefixes_formulas_and_leaves_numbers(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "cell.csv"
    for name, (typed, _) in FORMULAS.items():
        quote = '"' if "'" in typed else "'"
        assert front.errors(f"put S {name[1:]} {quote}{typed}{quote}") == []
    for name, (typed, _) in NUMBERS.items():
        assert front.errors(f"put {name[0]} {name[1:]} {typed}") == []
    names = [*FORMULAS, *NUMBERS]
    front.run("watch " + " ".join(f"{name[0]} {name[1:]}" for name in names))
    front.until(lambda: len(front.rows) == len(names), "the rows")
    front.run(f"log {path}")
    front.until(lambda: path.exists() and path.read_bytes().count(b"\r\n") >= 3, "rows")
    front.run("log stop")
    data = path.read_bytes()
    rows = assert_one_row_per_line(data, 1 + len(names))
    assert rows[0] == ["time", *names]
    for row in by_column(rows):
        assert {name: row[name] for name in names} == {
            name: cell for name, (_, cell) in {**FORMULAS, **NUMBERS}.items()
        }
    # Each prefixed cell quoted (OWASP); the numbers bare, as they were.
    assert b',"\'=HYPERLINK(""x"")",' in data
    assert b",\"'+cmd|' /C calc'!A0\"," in data
    assert b',"\'@SUM(1)",' in data
    assert b",-5,-1500,2.5\r\n" in data


def test_the_console_log_escapes_what_a_controller_string_holds(tmp_path: Path) -> None:
    server = RecordingServer(hostile_controller)
    path = tmp_path / "hostile.csv"
    engine = Engine("127.0.0.1", server.port, interval=0.02, timeout=1.0)
    engine.start()
    front = Front(engine)
    try:
        front.run("watch S 1 I 1")
        front.until(lambda: "S1" in front.rows and front.rows["S1"].variant is not None, "S1")
        front.run(f"log {path}")
        front.until(lambda: path.exists() and path.read_bytes().count(b"\r\n") >= 4, "rows")
        front.run("log stop")
    finally:
        engine.stop()
        server.close()
    rows = assert_one_row_per_line(path.read_bytes(), 3)
    assert rows[0] == ["time", "S1", "I1"]
    assert [(row["S1"], row["I1"]) for row in by_column(rows)] == [(HOSTILE_CELL, "-5")] * (
        len(rows) - 1
    )


@pytest.mark.parametrize(
    ("text", "cell"),
    [
        ("a\rb", "a\\x0db"),
        ("\rcmd", "'\\x0dcmd"),
        ("\t=1+1", "'\\x09=1+1"),
        ("-", "'-"),
        ("=", "'="),
        ("nul\x00del\x7fcsi\x9b", "nul\\x00del\\x7fcsi\\x9b"),
        ("line\u2028sep\u0085nel", "line\\u2028sep\\x85nel"),
        ("\u202egnp.exe", "\\u202egnp.exe"),
        ("'already quoted", "'already quoted"),
        ("", ""),
        ("RC8 simulator", "RC8 simulator"),
    ],
)
def test_each_text_cell_reads_back_as_shown_one_row_per_line(
    tmp_path: Path, text: str, cell: str
) -> None:
    path = tmp_path / "cells.csv"
    s1, i1 = VarRef(kind_of("S"), 1), VarRef(kind_of("I"), 1)
    log = CsvLog(str(path), [s1, i1])
    log.write(1_700_000_000.0, {s1: Variant(VT.BSTR, text), i1: Variant(VT.I4, -5)})
    log.write(1_700_000_001.0, {s1: Variant(VT.BSTR, text), i1: Variant(VT.I4, -5)})
    log.close()
    data = path.read_bytes()
    rows = assert_one_row_per_line(data, 3)
    assert [row[1:] for row in rows[1:]] == [[cell, "-5"]] * 2
    if cell.startswith("'"):
        assert b',"' + cell.encode() + b'",' in data  # a prefixed cell is quoted


# ------------------------------------------------------------- the CLI: watch --log-csv


@pytest.mark.slow
def test_watch_log_csv_prefixes_formulas_from_the_simulator(
    env: dict[str, str],
    tmp_path: Path,
) -> None:
    log = tmp_path / "watch.csv"
    names = [*FORMULAS, *NUMBERS]
    with SimulatorThread() as sim:
        put_as_typed(sim.host, sim.port, {**FORMULAS, **NUMBERS})
        words = [word for name in names for word in (name[0], name[1:])]
        result = cli(
            env, "-H", sim.host, "-p", str(sim.port), "watch", *words,
            "--count", "2", "--every", "0", "--log-csv", str(log),
        )  # fmt: skip
    assert result.returncode == 0, result.stderr
    data = log.read_bytes()
    rows = assert_one_row_per_line(data, 1 + len(names))
    assert rows[0] == ["time", *names] and len(rows) == 3
    for row in by_column(rows):
        assert {name: row[name] for name in names} == {
            name: cell for name, (_, cell) in {**FORMULAS, **NUMBERS}.items()
        }
    assert b',"\'=HYPERLINK(""x"")",' in data
    assert b",-5,-1500,2.5\r\n" in data


@pytest.mark.slow
def test_watch_log_csv_escapes_what_a_controller_string_holds(
    env: dict[str, str],
    tmp_path: Path,
    recording,
) -> None:
    server = recording(hostile_controller)
    log = tmp_path / "watch.csv"
    words = ["watch", "S", "1", "I", "1", "--count", "3", "--every", "0", "--log-csv", str(log)]
    result = cli(env, *server.args, *words)
    assert result.returncode == 0, result.stderr
    rows = assert_one_row_per_line(log.read_bytes(), 3)
    assert rows[0] == ["time", "S1", "I1"]
    assert [(row["S1"], row["I1"]) for row in by_column(rows)] == [(HOSTILE_CELL, "-5")] * 3
