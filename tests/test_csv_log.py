"""``log FILE.csv`` / ``--log-csv``: the watched values, one CSV row per poll cycle,
read back with the csv module as a spreadsheet or a script would."""

from __future__ import annotations

import contextlib
import csv
import os
import re
import select
import threading
from collections.abc import Callable, Iterator
from datetime import datetime
from pathlib import Path
from typing import TypeVar

import pytest

from rac_console.engine import Engine, Status
from rac_console.engine.watch.csvlog import columns_of
from rac_console.protocol import InputError
from tests.support.drivers import Front
from tests.support.servers import RecordingServer

P1_COLUMNS = ["P1.X", "P1.Y", "P1.Z", "P1.Rx", "P1.Ry", "P1.Rz", "P1.Fig"]
T = TypeVar("T")
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


def test_a_file_with_other_columns_is_refused_and_left_alone(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "cell.csv"
    path.write_text("time,I1\r\n2026-01-01T00:00:00.000+00:00,5\r\n")
    before = path.read_bytes()
    front.run("watch I 2")
    (error,) = front.errors(f"log {path}")
    assert "holds other columns: column 2 is 'I1', this log's is 'I2'" in error
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
    assert front.alerts == [
        "CSV log not started: cannot write the CSV log /dev/full: No space left on device"
    ]


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


# ----------------------------------------------------------------- appending


@pytest.mark.parametrize(
    "before",
    [b"time,I0\r\n2026-01-01T00:00:00.000+00:00,5", b"time,I0", b"time,I0\r\n1,2\r"],
    ids=["a row without its line end", "a header without its line end", "a bare CR"],
)
def test_appending_to_a_file_without_a_last_line_end_ends_that_line_first(
    front: Front, tmp_path: Path, before: bytes
) -> None:
    path = tmp_path / "cut.csv"
    path.write_bytes(before)
    front.run("watch I 0")
    front.until(lambda: "I0" in front.rows, "the row")
    (said,) = front.run(f"log {path}")
    assert said.startswith(f"appending to {path}: 1 variable,")
    kept = read_rows(Path(str(path)))[: before.count(b"\n") + 1]
    front.until(lambda: len(read_rows(path)) >= len(kept) + 2, "rows")
    front.run("log stop")
    rows = read_rows(path)
    assert rows[: len(kept)] == kept
    assert all(ISO_MS.fullmatch(row[0]) and len(row) == 2 for row in rows[len(kept) :]), rows
    assert b"\r\r\n" not in path.read_bytes()


def test_a_header_saved_back_by_excel_with_a_bom_is_appended_to(
    front: Front, tmp_path: Path
) -> None:
    path = tmp_path / "excel.csv"
    path.write_bytes("\ufefftime,I0\r\n2026-01-01T00:00:00.000+00:00,5\r\n".encode())
    front.run("watch I 0")
    (said,) = front.run(f"log {path}")
    assert said.startswith(f"appending to {path}")
    front.until(lambda: len(read_rows(path)) >= 3, "rows")
    assert path.read_bytes().startswith(
        b"\xef\xbb\xbftime,I0\r\n2026-01-01T00:00:00.000+00:00,5\r\n"
    )
    assert sum(row[0].endswith("time") for row in read_rows(path)) == 1


@pytest.mark.parametrize(
    ("header", "difference"),
    [
        (b"Time,I0\r\n", "column 1 is 'Time', this log's is 'time'"),
        (b"t\xedme,I0\r\n", "column 1 is 't\ufffdme', this log's is 'time'"),
        (b"time,I0,I1\r\n", "it has 3 columns, this log has 2"),
        (b"time\r\n", "it has 1 column, this log has 2"),
        ("\ufefftime,\ufeffI0\r\n".encode(), "column 2 is '\\ufeffI0', this log's is 'I0'"),
    ],
)
def test_a_refused_header_names_its_first_difference(
    front: Front, tmp_path: Path, header: bytes, difference: str
) -> None:
    path = tmp_path / "other.csv"
    path.write_bytes(header)
    front.run("watch I 0")
    (error,) = front.errors(f"log {path}")
    assert difference in error, error
    assert path.read_bytes() == header
    listed = re.search(r"from column \d+ it has (.*); this log has (.*)\)", error)
    assert listed is not None and listed[1] != listed[2], error


# ------------------------------------------------------------ failures stick


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="a device that is always full (Linux)")
def test_a_log_that_fails_at_once_is_an_error_answer_not_a_success(front: Front) -> None:
    front.run("watch I 0")
    front.until(lambda: "I0" in front.rows, "the row")
    assert front.run("log /dev/full") == [
        "CSV log not started: cannot write the CSV log /dev/full: No space left on device"
    ]
    assert front.errors("log") == []
    front.until(lambda: front.status is not None and front.status.csv_failure is not None, "")
    assert front.alerts == []  # the answer said it: once


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="a device that is always full (Linux)")
def test_a_failed_log_still_sets_the_exit_status_after_a_good_one(
    front: Front, tmp_path: Path
) -> None:
    from rac_console.present.status import status_text

    front.run("watch I 0")
    front.run("log /dev/full")
    path = tmp_path / "ok.csv"
    (said,) = front.run(f"log {path}")
    assert said.startswith(f"logging to {path}")
    front.until(lambda: front.status is not None and front.status.csv_log == str(path), "")
    assert front.status is not None
    line = status_text(front.status, None, 0.0).plain
    assert " CSV " in line and "CSV LOG STOPPED" not in line
    front.run("log stop")
    front.until(lambda: front.status is not None and front.status.csv_log is None, "")
    assert front.status is not None and front.status.exit_status(0) == 4
    assert "CSV LOG STOPPED" in status_text(front.status, None, 0.0).plain


def test_log_csv_whose_header_differs_fails_at_the_first_cycle_and_says_so(
    tmp_path: Path,
) -> None:
    from rac_console.present.status import status_text

    path = tmp_path / "case.csv"
    path.write_bytes(b"Time,I0\r\n")
    front = engine_front(log_csv=str(path))
    try:
        front.run("watch I 0")
        front.until(lambda: bool(front.alerts), "the alert")
        assert front.alerts[0].startswith(f"CSV log not started: {path} holds other columns")
        front.until(lambda: front.status is not None and front.status.csv_failure is not None, "")
        assert front.status is not None and front.status.exit_status(0) == 4
        assert "CSV LOG STOPPED" in status_text(front.status, None, 0.0).plain
    finally:
        front.engine.stop()
    assert path.read_bytes() == b"Time,I0\r\n"


# --------------------------------------------------------------------- pipes

needs_fifo = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes (POSIX)")


def within(seconds: float, call: Callable[[], T]) -> T:
    """``call()``'s result, or a test failure when it does not return in time."""
    box: list[T] = []
    thread = threading.Thread(target=lambda: box.append(call()), daemon=True)
    thread.start()
    thread.join(seconds)
    assert box, f"{call} still blocked after {seconds} s"
    return box[0]


def release_writer(path: Path) -> None:
    """Unblock a writer stuck opening ``path`` (the defect under test), for clean-up."""
    with contextlib.suppress(OSError):
        os.close(os.open(path, os.O_RDONLY | os.O_NONBLOCK))


class PipeReader:
    """A program reading the pipe: opened before the log starts, reads until stopped."""

    def __init__(self, path: Path) -> None:
        self.data = bytearray()
        self._fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        while not self._stop.is_set():
            select.select([self._fd], [], [], 0.05)
            try:
                chunk = os.read(self._fd, 65536)
            except BlockingIOError:
                continue
            if chunk:
                self.data += chunk
            else:  # no writer (yet, or any more)
                self._stop.wait(0.01)

    def rows(self) -> list[list[str]]:
        text = bytes(self.data).decode()
        return list(csv.reader(text.splitlines()))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)
        os.close(self._fd)


@needs_fifo
def test_a_pipe_with_no_reader_is_refused_not_waited_for(front: Front, tmp_path: Path) -> None:
    fifo = tmp_path / "ff"
    os.mkfifo(fifo)
    front.run("watch I 0")
    try:
        errors = within(5, lambda: front.errors(f"log {fifo}"))
    finally:
        release_writer(fifo)
    assert errors == [
        f"CSV log not started: no program is reading the pipe {fifo}: start the reader first"
    ]


@needs_fifo
def test_log_csv_to_a_pipe_with_no_reader_is_refused_at_start(tmp_path: Path) -> None:
    fifo = tmp_path / "ff"
    os.mkfifo(fifo)

    def make() -> str:
        try:
            Engine(None, log_csv=str(fifo))
        except InputError as exc:
            return str(exc)
        return "started"

    try:
        said = within(5, make)
    finally:
        release_writer(fifo)
    assert said == f"no program is reading the pipe {fifo}: start the reader first"


@needs_fifo
@pytest.mark.parametrize("at_start", [False, True], ids=["log FILE", "--log-csv"])
def test_a_program_reading_a_pipe_gets_the_header_and_the_rows(
    tmp_path: Path, at_start: bool
) -> None:
    fifo = tmp_path / "ff"
    os.mkfifo(fifo)
    reader = PipeReader(fifo)
    try:
        front = within(5, lambda: engine_front(log_csv=str(fifo) if at_start else None))
    except BaseException:
        release_writer(fifo)
        reader.close()
        raise
    try:
        front.run("watch I 0")
        if not at_start:
            (said,) = within(5, lambda: front.run(f"log {fifo}"))
            assert said.startswith(f"logging to {fifo}: 1 variable,")
        front.until(lambda: len(reader.rows()) >= 3, "rows through the pipe")
        header, *rows = reader.rows()
        assert header == ["time", "I0"]
        assert all(ISO_MS.fullmatch(row[0]) for row in rows)
    finally:
        release_writer(fifo)
        front.engine.stop()
        reader.close()


# ------------------------------------------------------------------- outages


@pytest.mark.slow  # over half a second
def test_rows_go_on_with_empty_cells_while_the_controller_is_unreachable(
    tmp_path: Path,
) -> None:
    server = RecordingServer(lambda line: b"0,3,77\r")
    path = tmp_path / "outage.csv"
    engine = Engine("127.0.0.1", server.port, interval=0.02, timeout=1.0)
    engine.start()
    front = Front(engine)
    try:
        front.run("watch I 1")
        front.run(f"log {path}")
        front.until(lambda: any(row[1:] == ["77"] for row in read_rows(path)), "a good row")
        server.close()
        front.until(lambda: front.status is not None and front.status.connection == "lost", "")
        lost = len(read_rows(path))
        # Retries 0.5 s then 1 s apart: a row each, its cell empty (no connection).
        front.until(lambda: len(read_rows(path)) >= lost + 2, "rows during the outage")
        assert all(row[1:] == [""] for row in read_rows(path)[lost:])
    finally:
        engine.stop()
        server.close()


# ------------------------------------------------------------------ details


def test_counts_are_singular_for_one(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "one.csv"
    front.run("interval 60")  # one cycle now, the next a minute later
    front.run(f"log {path}")
    front.run("watch I 0")
    front.until(lambda: len(read_rows(path)) == 2, "the row")
    assert front.run("log") == [f"logging 1 variable to {path}: 1 row so far"]
    assert front.run("log stop") == [f"CSV log stopped: 1 row in {path}"]


def test_a_path_under_home_is_expanded(
    front: Front, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    home = tmp_path / "home"
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("USERPROFILE", str(home))
    monkeypatch.chdir(tmp_path)
    front.run("watch I 0")
    (said,) = front.run(f"log ~{os.sep}x.csv")
    assert said.startswith(f"logging to {home / 'x.csv'}")
    front.until(lambda: len(read_rows(home / "x.csv")) >= 2, "rows")
    assert not (tmp_path / "~").exists()


async def test_the_repl_says_when_a_watch_is_not_in_the_csv_columns(tmp_path: Path) -> None:
    from tests.support.drivers import Driver

    path = tmp_path / "repl.csv"
    driver = Driver(tmp_path)
    failed: list[AssertionError] = []

    async def steps(d: Driver) -> None:
        try:
            d.type(f"log {path}\r")
            await d.until(lambda out: "from the first poll cycle" in out, "the log")
            d.type("watch I 0\r")
            await d.until(lambda out: len(read_rows(path)) >= 2, "the log's first rows")
            d.type("\r")
            # Ended, its key reader gone: a line typed while the watch reads keys is taken
            # as the Enter that ends it (its rows may not have reached the REPL yet, so
            # "no rows" can hold before the watch has even begun).
            await d.until(lambda out: d.watches_ended == 1, "the watch to end")
            d.type("watch I 1\r")
            await d.until(lambda out: "not in the CSV log's columns" in out, "the warning")
        except AssertionError as exc:
            failed.append(exc)
        if d.watches_ended < d.watches_begun:
            d.type("\r")  # leave the live watch: the REPL can then quit
            await d.until(lambda out: d.watches_ended == d.watches_begun, "the watch to end")

    out = await driver.run(steps)
    if failed:
        raise failed[0]
    assert out.count("not in the CSV log's columns") == 1
