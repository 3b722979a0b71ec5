"""``log FILE.csv`` / ``--log-csv``: the watched values, one CSV row per poll cycle,
read back with the csv module as a spreadsheet or a script would."""

from __future__ import annotations

import csv
import re
from collections.abc import Iterator
from datetime import datetime
from pathlib import Path

import pytest
from test_engine import Front

from rac_console.engine import Engine, Status
from rac_console.engine.csvlog import columns_of
from rac_console.protocol import InputError

P1_COLUMNS = ["P1.X", "P1.Y", "P1.Z", "P1.Rx", "P1.Ry", "P1.Rz", "P1.Fig"]
ISO_MS = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}[+-]\d\d:\d\d")


def read_rows(path: Path) -> list[list[str]]:
    if not path.exists():
        return []
    with path.open(newline="", encoding="utf-8") as handle:
        return list(csv.reader(handle))


def engine_front(**options: object) -> Front:
    engine = Engine(None, interval=0.02, timeout=1.0, **options)  # type: ignore[arg-type]
    engine.start()
    return Front(engine)


@pytest.fixture
def front() -> Iterator[Front]:
    front = engine_front()
    try:
        yield front
    finally:
        front.engine.stop()


def test_each_poll_cycle_is_one_row_with_a_column_per_field(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "cell.csv"
    front.run("watch P 1 IO 128-129 I 0 S 1")
    front.until(lambda: len(front.rows) == 5, "the rows")
    (said,) = front.run(f"log {path}")
    assert said.startswith(f"logging to {path}: 5 variables")
    # I0 counts at 10 Hz: each row holds its own cycle's value, so some rows differ.
    front.until(lambda: len({row[10] for row in read_rows(path)[1:]}) > 1, "I0 moving")
    header, *rows = read_rows(path)
    assert header == ["time", *P1_COLUMNS, "IO128", "IO129", "I0", "S1"]
    for row in rows:
        assert len(row) == len(header)
        assert ISO_MS.fullmatch(row[0]), row[0]
        assert row[1:8] == ["350", "0", "450", "180", "0", "180", "5"]
        assert row[8:10] == ["1", "0"]
        assert row[11] == "RC8 simulator"
    times = [datetime.fromisoformat(row[0]) for row in rows]
    assert times == sorted(times)


def test_stop_then_log_again_appends_under_the_same_header(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "cell.csv"
    front.run("watch I 1 F 1")
    front.run(f"log {path}")
    front.until(lambda: len(read_rows(path)) >= 3, "rows")
    (stopped,) = front.run("log stop")
    kept = read_rows(path)
    assert stopped == f"CSV log stopped: {len(kept) - 1} rows in {path}"
    (said,) = front.run(f"log {path}")
    assert said.startswith(f"appending to {path}")
    front.until(lambda: len(read_rows(path)) >= len(kept) + 2, "more rows")
    rows = read_rows(path)
    assert rows[: len(kept)] == kept
    assert [row for row in rows if row[0] == "time"] == [["time", "I1", "F1"]]


def test_a_file_with_other_columns_is_refused_and_left_alone(
    front: Front, tmp_path: Path
) -> None:
    path = tmp_path / "cell.csv"
    path.write_text("time,I1\r\n2026-01-01T00:00:00.000+00:00,5\r\n")
    before = path.read_bytes()
    front.run("watch I 2")
    (error,) = front.errors(f"log {path}")
    assert "holds other columns (I1), not these (I2)" in error
    assert path.read_bytes() == before
    assert front.run("log") == ["not logging: log FILE.csv starts a CSV log of the watched values"]


def test_logging_before_anything_is_watched_starts_with_the_first_cycle(
    front: Front, tmp_path: Path
) -> None:
    path = tmp_path / "later.csv"
    (said,) = front.run(f"log {path}")
    assert "from the first poll cycle" in said
    front.run("watch IO 130 I 1")
    front.until(lambda: len(read_rows(path)) >= 3, "rows")
    assert read_rows(path)[0] == ["time", "IO130", "I1"]
    (error,) = front.errors(f"log {tmp_path / 'other.csv'}")
    assert error == f"already logging to {path}: log stop first"


def test_log_csv_at_start(tmp_path: Path) -> None:
    path = tmp_path / "start.csv"
    front = engine_front(log_csv=str(path))
    try:
        front.run("watch D 1")
        front.until(lambda: len(read_rows(path)) >= 2, "rows")
        assert read_rows(path)[1][1] == "3.141592653589793"
        front.until(lambda: front.status is not None and front.status.csv_log == str(path), "")
    finally:
        front.engine.stop()


def test_log_csv_that_cannot_be_written_is_refused_at_start(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot write the CSV log"):
        Engine(None, log_csv=str(tmp_path / "no-such-dir" / "x.csv"))


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="a device that is always full (Linux)")
def test_a_full_disk_is_said_once_and_polling_goes_on(tmp_path: Path) -> None:
    front = engine_front(log_csv="/dev/full")
    try:
        front.run("watch I 0")
        front.until(lambda: bool(front.alerts), "the failure")
        polls = len(front.frames)
        front.until(lambda: len(front.frames) > polls + 20, "more polls")
        status: Status | None = front.status
        assert status is not None and status.csv_failure is not None
        assert status.exit_status(0) == 4
    finally:
        front.engine.stop()
    assert front.alerts == ["CSV log stopped: No space left on device after 0 rows (/dev/full)"]


def test_columns_of_every_kind() -> None:
    from rac_console.commands.language import VarRef
    from rac_console.protocol import kind_of

    variables = [VarRef(kind_of(code), 3) for code in ("V", "J", "T", "IO")]
    assert columns_of(variables) == [
        "time",
        "V3.X",
        "V3.Y",
        "V3.Z",
        *(f"J3.J{n}" for n in range(1, 9)),
        *(f"T3.{f}" for f in ("X", "Y", "Z", "Ox", "Oy", "Oz", "Ax", "Ay", "Az", "Fig")),
        "IO3",
    ]


@pytest.mark.slow
def test_an_unwritable_log_csv_is_one_line_and_exit_2(tmp_path: Path) -> None:
    import subprocess
    import sys

    path = tmp_path / "missing" / "x.csv"
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "--log-csv", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2
    assert result.stderr.strip() == (
        f"rac-console: cannot write the CSV log {path}: No such file or directory"
    )
