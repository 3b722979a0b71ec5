"""``record FILE`` and ``transcript FILE`` start and stop from inside the console and
the REPL (issue 20): the interesting moment is rarely foreseen at start."""

from __future__ import annotations

import json
from pathlib import Path

from tests.support.drivers import Front


def test_record_starts_and_stops_inside(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "cell.jsonl"
    front.run("get I 1")  # before: not recorded
    [said] = front.run(f"record {path}")
    assert "record" in said and str(path) in said
    front.until(lambda: front.status is not None and front.status.recording == str(path), "status")
    front.run("get I 2")
    [said] = front.run("record stop")
    assert "stopped" in said
    front.run("get I 3")  # after: not recorded
    texts = [json.loads(line)["text"] for line in path.read_text().splitlines()]
    assert texts[0] == "GET:RC8:2:I:" and len(texts) == 2, texts


def test_transcript_starts_and_stops_inside(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "cell.log"
    front.run(f"transcript {path}")
    front.run("get I 7")
    front.run("transcript stop")
    front.run("get I 8")
    text = path.read_text()
    assert "GET:RC8:7:I:" in text and "GET:RC8:8:I:" not in text


def test_record_says_where_and_refuses_a_second(front: Front, tmp_path: Path) -> None:
    assert "no record running" in front.run("record")[0]
    front.run(f"record {tmp_path / 'a.jsonl'}")
    assert "a.jsonl" in front.run("record")[0]
    [error] = front.errors(f"record {tmp_path / 'b.jsonl'}")
    assert "already goes to" in error
    [error] = front.errors(f"transcript {tmp_path / 'missing' / 'x.log'}")
    assert "x.log" in error  # cannot be opened: one line, nothing started
