"""A cell's files: one ``--record``, one ``--log`` transcript and one CSV log for all its
targets, each line naming the target it came from.

Two real targets on loopback: robotA is the built-in simulator (``SimulatorThread``),
robotB a server written here that answers every S with a hostile string (a formula,
ESC). Every wait has a deadline; nothing sleeps and hopes.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.commands.target import Target
from rac_console.engine import EngineOptions
from rac_console.engine.cell.cell import Cell
from rac_console.sim.replay import load_recordings
from rac_console.sim.thread import SimulatorThread
from tests.support.cells import CellFront
from tests.support.servers import RecordingServer

DEADLINE = 10.0
HOSTILE = "=cmd|' /C calc'!A0\x1b[2J"
HOSTILE_CELL = "'=cmd|' /C calc'!A0\\x1b[2J"


def hostile(line: bytes) -> bytes:
    """robotB: S answers HOSTILE, I answers 7, IO and the rest 0 (I4)."""
    if line.endswith(b":S:"):
        return b"0,8," + HOSTILE.encode("ascii") + b"\r"
    if line.endswith(b":I:"):
        return b"0,3,7\r"
    return b"0,3,0\r"


@pytest.fixture
def robots() -> Iterator[tuple[SimulatorThread, RecordingServer]]:
    with SimulatorThread() as a:
        b = RecordingServer(hostile)
        try:
            yield a, b
        finally:
            b.close()


def start_cell(
    robots: tuple[SimulatorThread, RecordingServer], **files: str
) -> tuple[Cell, CellFront]:
    a, b = robots
    cell = Cell(
        [("robotA", Target("127.0.0.1", a.port)), ("robotB", Target("127.0.0.1", b.port))],
        options=EngineOptions(interval=0.02, timeout=1.0, **files),  # type: ignore[arg-type]
    )
    cell.start()
    return cell, CellFront(cell)


def csv_rows(path: Path) -> list[list[str]]:
    if not path.exists():
        return []
    return list(csv.reader(io.StringIO(path.read_bytes().decode("utf-8"), newline="")))


def test_a_cell_writes_one_record_one_transcript_and_one_csv_naming_each_target(
    robots: tuple[SimulatorThread, RecordingServer], tmp_path: Path
) -> None:
    record, transcript, log = tmp_path / "c.jsonl", tmp_path / "c.log", tmp_path / "c.csv"
    cell, front = start_cell(
        robots, record=str(record), transcript=str(transcript), log_csv=str(log)
    )
    try:
        front.run("@robotA watch IO 128 I 10")
        front.run("@robotB watch IO 128 S 1")

        def both_have_rows() -> bool:
            rows = csv_rows(log)[1:]
            filled = {(r[1] != "", r[3] != "") for r in rows if len(r) == 5}
            return (True, False) in filled and (False, True) in filled

        front.until(both_have_rows, "CSV rows of both targets")
    finally:
        cell.stop()

    lines = [json.loads(line) for line in record.read_text().splitlines()]
    assert {line["target"] for line in lines} == {"robotA", "robotB"}
    assert all(set(line) >= {"t", "target", "dir", "text"} for line in lines)
    texts = {(line["target"], line["text"]) for line in lines}
    assert ("robotA", "GET:RC8:10:I:") in texts and ("robotB", "GET:RC8:1:S:") in texts
    assert ("robotB", "0,8," + HOSTILE.replace("\x1b", "\\x1b")) in texts

    said = transcript.read_text(encoding="utf-8").splitlines()
    assert any(" robotA TX GET:RC8:10:I:" in line for line in said)
    assert any(" robotB RX 0,8,=cmd|' /C calc'!A0\\x1b[2J" in line for line in said)
    assert all(" robotA " in line or " robotB " in line for line in said), said
    assert "\x1b" not in transcript.read_text(encoding="utf-8")

    data = log.read_bytes()
    assert b"\x1b" not in data
    rows = csv_rows(log)
    assert rows[0] == ["time", "robotA.IO128", "robotA.I10", "robotB.IO128", "robotB.S1"]
    assert all(len(row) == 5 for row in rows), rows
    a_rows = [row for row in rows[1:] if row[1]]
    b_rows = [row for row in rows[1:] if row[3]]
    assert a_rows and b_rows
    assert all(row[3:] == ["", ""] for row in a_rows)  # not read in robotA's cycle
    assert all(row[1:3] == ["", ""] for row in b_rows)
    assert {row[4] for row in b_rows} == {HOSTILE_CELL}
    assert b",\"'=cmd|' /C calc'!A0\\x1b[2J\"\r\n" in data  # prefixed, quoted, escaped


def test_a_recorded_cell_loads_as_one_recording_per_target(
    robots: tuple[SimulatorThread, RecordingServer], tmp_path: Path
) -> None:
    record = tmp_path / "c.jsonl"
    cell, front = start_cell(robots, record=str(record))
    try:
        front.run("@robotA get I 10")
        front.run("@robotB get I 10")
    finally:
        cell.stop()
    found = {r.target: r for r in load_recordings(str(record))}
    assert set(found) == {"robotA", "robotB"}
    assert found["robotB"].answers[("I", 10)] == [b"0,3,7\r"]
    assert found["robotA"].answers[("I", 10)][0].startswith(b"0,3,")


def test_a_cell_log_started_later_covers_every_target_and_stops_for_all(
    robots: tuple[SimulatorThread, RecordingServer], tmp_path: Path
) -> None:
    log = tmp_path / "later.csv"
    cell, front = start_cell(robots)
    try:
        front.run("@robotA watch I 10")
        front.run("@robotB watch I 10")
        (said,) = front.run(f"@robotB log {log}")
        assert "every target" in said
        front.until(lambda: len(csv_rows(log)) >= 5, "rows")
        assert csv_rows(log)[0] == ["time", "robotA.I10", "robotB.I10"]
        (said,) = front.run("@robotA log stop")
        assert said.startswith("CSV log stopped")
        (said,) = front.run("@robotB log")
        assert said.startswith("not logging")
    finally:
        cell.stop()


def test_a_cell_record_started_at_one_target_records_them_all(
    robots: tuple[SimulatorThread, RecordingServer], tmp_path: Path
) -> None:
    record = tmp_path / "later.jsonl"
    cell, front = start_cell(robots)
    try:
        (said,) = front.run(f"record {record}")
        assert "every target" in said
        front.run("@robotA get I 10")
        front.run("@robotB get I 10")
        (said,) = front.run("@robotB record stop")
        assert said.startswith("record stopped")
        front.run("@robotA get I 11")
    finally:
        cell.stop()
    lines = [json.loads(line) for line in record.read_text().splitlines()]
    assert {line["target"] for line in lines} == {"robotA", "robotB"}
    assert not any("11" in line["text"] for line in lines)


def test_a_file_that_fails_is_said_once_and_stops_for_every_target(
    robots: tuple[SimulatorThread, RecordingServer],
) -> None:
    cell, front = start_cell(robots, record="/dev/full")
    try:
        front.run("@robotA get I 10")
        front.run("@robotB get I 10")
        front.run("@robotA get I 10")
        front.until(lambda: bool(front.alerts), "the alert")
    finally:
        cell.stop()
    front.drain()
    said = [text for _, text in front.alerts if "recording stopped" in text]
    assert len(said) == 1, front.alerts
