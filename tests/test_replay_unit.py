"""``sim --replay``'s pure part (rac_console/sim/replay.py), and the in-process server
serving it: a record file becomes per-variable answers, served in order.

The subprocess tests (a file recorded by the real CLI, replayed by ``rac-console sim``)
are in test_replay.py.
"""

from __future__ import annotations

import asyncio
import json
import os
import sys
import threading
from collections.abc import Mapping, Sequence
from pathlib import Path

import pytest

from rac_console.engine.files.recorder import FrameRecorder
from rac_console.protocol import escape_bytes, parse_response
from rac_console.protocol.hresult import (
    E_ACCESSDENIED,
    E_INVALIDARG,
    E_INVALIDCOMMAND,
    E_INVALIDRCVPACKET,
    E_NOTIMPL,
)
from rac_console.session import Frame
from rac_console.session.types import MAX_REPLY_LINE
from rac_console.sim import replay
from rac_console.sim.controller import SimulatedController
from rac_console.sim.faults import FaultSettings
from rac_console.sim.replay import (
    MAX_LINE_BYTES,
    ReplayController,
    ReplayError,
    load_recording,
    read_records,
    unescape_text,
)
from rac_console.sim.server import SimulatorServer

DEADLINE = 10.0  # a wait this long means hung: never a figure a test checks


def frames(*pairs: tuple[str, str], **flags: bool) -> list[dict[str, object]]:
    """Records of request/answer pairs: ("GET:RC8:10:I:", "0,3,1")."""
    out: list[dict[str, object]] = []
    for request, answer in pairs:
        out.append({"t": 1.0, "dir": "tx", "text": request})
        out.append({"t": 1.1, "dir": "rx", "text": answer, "rtt_ms": 0.2, **flags})
    return out


def write(path: Path, records: Sequence[Mapping[str, object]]) -> Path:
    path.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    return path


def recorded(records: Sequence[Mapping[str, object]]):
    lines = [json.dumps(r).encode() + b"\n" for r in records]
    return read_records(lines, "test.jsonl")


def ask(controller: ReplayController, line: str) -> bytes:
    reply, close = controller.handle(line.encode("ascii"))
    assert not close
    return reply


def code(reply: bytes) -> int:
    return parse_response(reply[:-1].decode("ascii")).code


I10 = [("GET:RC8:10:I:", "0,3,1"), ("GET:RC8:10:I:", "0,3,2"), ("GET:RC8:10:I:", "0,3,3")]


# ---------------------------------------------------------------- the file


def test_each_variable_gets_its_answers_in_order() -> None:
    recording = recorded(
        frames(I10[0], ("GET:RC8:1:S:", "0,8,a"), I10[1], ("GET:RC8:1:S:", "0,8,b"), I10[2])
    )
    assert recording.answers == {
        ("I", 10): [b"0,3,1\r", b"0,3,2\r", b"0,3,3\r"],
        ("S", 1): [b"0,8,a\r", b"0,8,b\r"],
    }
    assert recording.count == 5


def test_requests_are_keyed_as_the_controller_reads_them() -> None:
    recording = recorded(
        frames(
            ("GET:RC8:10:I:", "0,3,1"), ("get:rc8:010:i:", "0,3,2"), ("  GET:RC8:10:I:", "0,3,3")
        )
    )
    assert recording.answers == {("I", 10): [b"0,3,1\r", b"0,3,2\r", b"0,3,3\r"]}
    controller = ReplayController(recording)
    assert [
        ask(controller, line) for line in ("gEt:Rc8:10:I:", "GET:RC8:0010:i:", "\tGET:RC8:10:I:")
    ] == [
        b"0,3,1\r",
        b"0,3,2\r",
        b"0,3,3\r",
    ]


def test_only_answered_gets_are_used() -> None:
    records: list[Mapping[str, object]] = [
        {"dir": "tx", "text": "GET:RC8:1:I:"},  # timed out: the next request came
        *frames(("GET:RC8:2:I:", "0,3,2")),
        {"dir": "rx", "text": "stray"},  # nobody asked
        {"dir": "tx", "text": "GET:RC8:3:I:"},
        {"dir": "rx", "text": "hello", "unsolicited": True},  # a stray while it waits...
        {"dir": "rx", "text": "0,3,3", "rtt_ms": 1.0},  # ...and then its answer
        {"dir": "tx", "text": "GET:RC8:4:I:"},
        {"dir": "rx", "text": "0,3", "partial": True},  # cut off: no answer
        {"dir": "tx", "text": "GET:RC8:5:I:"},
        {"dir": "rx", "text": "0,8,x", "refused": "wrong VARTYPE"},  # the session refused it
        *frames(("PUT:RC8:6:I:3,6", "0"), ("SIM:GET:", "0,8,none"), ("GET:RC8:7:I:3", "-1")),
        *frames(("GET:RC8:500:I:", "-2147024809")),  # an error answer: replayed as it was
        {"dir": "tx", "text": "GET:RC8:8:I:"},  # the last request, never answered
    ]
    recording = recorded(records)
    assert recording.answers == {
        ("I", 2): [b"0,3,2\r"],
        ("I", 3): [b"0,3,3\r"],
        ("I", 500): [b"-2147024809\r"],
    }
    assert (recording.unanswered, recording.unused_replies, recording.not_gets) == (4, 2, 3)
    line = recording.describe("hold")
    assert "3 variables, 3 answers" in line
    assert "4 requests with no answer" in line
    assert "hold the last" in line


def test_text_comes_back_as_the_bytes_recorded() -> None:
    every_byte = bytes(range(256))
    assert unescape_text(escape_bytes(every_byte)) == every_byte
    assert unescape_text("a\\\\x41") == b"a\\x41"
    for bad in ("\\", "\\q", "\\x4", "\\xZZ", "é", "\x1b[2J", "\x7f"):
        with pytest.raises(ValueError):
            unescape_text(bad)


def test_repeated_answers_share_one_bytes_object() -> None:
    recording = recorded(frames(*[("GET:RC8:1:I:", "0,3,7")] * 50))
    replies = recording.answers[("I", 1)]
    assert len(replies) == 50
    assert len({id(r) for r in replies}) == 1


# ------------------------------------------------------- files that are not


def test_a_missing_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(ReplayError, match=r"cannot read the replay file .*nope\.jsonl"):
        load_recording(str(tmp_path / "nope.jsonl"))


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("not json", r"line 3 is not JSON"),
        ("[" * 100_000, r"line 3 is not JSON"),
        ("[1, 2]", r"line 3 is not a recorded frame"),
        ('{"dir": "up", "text": "x"}', r"line 3: 'dir' must be"),
        ('{"dir": "rx"}', r"line 3: 'text' must be a string"),
        ('{"dir": "rx", "text": "\\\\q"}', r"line 3: 'text' is not as --record writes it"),
    ],
    ids=["text", "deep", "list", "dir", "no-text", "escape"],  # never the 100 KB line
)
def test_a_malformed_line_is_named_by_its_number(tmp_path: Path, line: str, message: str) -> None:
    path = tmp_path / "rec.jsonl"
    good = "".join(json.dumps(r) + "\n" for r in frames(I10[0]))
    path.write_text(good + line + "\n" + good, encoding="utf-8")
    with pytest.raises(ReplayError, match=message):
        load_recording(str(path))


def test_bytes_that_are_not_utf8_are_not_json(tmp_path: Path) -> None:
    path = tmp_path / "rec.jsonl"
    path.write_bytes(b'{"dir": "tx", "text": "GET:RC8:1:I:"}\n\xff\xfe\n')
    with pytest.raises(ReplayError, match="line 2 is not JSON"):
        load_recording(str(path))


def test_what_the_file_says_is_quoted_terminal_safe(tmp_path: Path) -> None:
    # Windows forbids control characters in file names: there only the file's text has them.
    name = "rec.jsonl" if sys.platform == "win32" else "rec\x1b[2J.jsonl"
    path = write(tmp_path / name, [{"dir": "\x1b]0;owned\x07", "text": ""}])
    with pytest.raises(ReplayError) as error:
        load_recording(str(path))
    text = str(error.value)
    assert "\x1b" not in text and "\x07" not in text
    assert "line 1" in text


def test_a_file_with_no_answered_get_is_refused(tmp_path: Path) -> None:
    for records in ([], frames(("PUT:RC8:1:I:3,1", "0")), [{"dir": "tx", "text": "GET:RC8:1:I:"}]):
        path = write(tmp_path / "rec.jsonl", records)
        with pytest.raises(ReplayError, match="nothing to replay"):
            load_recording(str(path))


# ------------------------------------------------------------ the limits


def test_the_longest_line_record_writes_is_within_the_line_limit(tmp_path: Path) -> None:
    """A reply as long as a session takes, every byte escaped: --record's longest line."""
    path = tmp_path / "rec.jsonl"
    recorder = FrameRecorder(str(path))
    recorder(Frame(1.0, "tx", b"GET:RC8:1:S:\r"))
    recorder(Frame(1.1, "rx", b"0,8," + b"\x1b" * (MAX_REPLY_LINE - 5) + b"\r", rtt=0.1))
    recorder.close()
    longest = max(len(line) for line in path.read_bytes().splitlines())
    assert MAX_REPLY_LINE * 4 < longest <= MAX_LINE_BYTES
    assert load_recording(str(path)).answers[("S", 1)][0].count(b"\x1b") == MAX_REPLY_LINE - 5


def test_a_line_of_the_limit_is_read_and_one_byte_more_is_refused(tmp_path: Path) -> None:
    good = "".join(json.dumps(r) + "\n" for r in frames(I10[0]))
    head, tail = '{"dir": "tx", "text": "GET:RC8:1:S:", "x": "', '"}'
    path = tmp_path / "rec.jsonl"
    for size, refused in ((MAX_LINE_BYTES, False), (MAX_LINE_BYTES + 1, True)):
        line = head + "y" * (size - len(head) - len(tail)) + tail
        assert len(line) == size
        path.write_bytes((good + line + "\n" + good).encode("ascii"))  # LF, on Windows too
        if refused:
            with pytest.raises(ReplayError, match=r"line 3 is longer than 512 KiB"):
                load_recording(str(path))
        else:
            assert load_recording(str(path)).count == 2
    path.write_bytes((good + line).encode("ascii"))  # the last line, with no newline
    with pytest.raises(ReplayError, match=r"line 3 is longer than"):
        load_recording(str(path))


def test_a_file_of_the_limit_is_read_and_one_byte_more_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pair = "".join(json.dumps(r) + "\n" for r in frames(I10[0]))
    path = tmp_path / "rec.jsonl"
    path.write_bytes((pair * 10).encode("ascii"))  # LF, on Windows too
    monkeypatch.setattr(replay, "MAX_FILE_BYTES", len(pair) * 10)
    assert load_recording(str(path)).count == 10
    with path.open("ab") as file:
        file.write(b"\n")  # a blank line: one byte more
    with pytest.raises(ReplayError, match=r"rec\.jsonl is larger than .*split"):
        load_recording(str(path))


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_a_stream_is_counted_as_it_is_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A pipe has no size to ask: reading stops once the limit is passed."""
    pair = ("".join(json.dumps(r) + "\n" for r in frames(I10[0]))).encode("ascii")
    monkeypatch.setattr(replay, "MAX_FILE_BYTES", len(pair) * 10)
    path = tmp_path / "pipe.jsonl"
    os.mkfifo(path)
    written: list[int] = []

    def feed() -> None:  # far more than the limit; stops when the reader goes away
        try:
            with open(path, "wb", buffering=0) as pipe:
                for _ in range(10_000):
                    written.append(pipe.write(pair) or 0)
        except BrokenPipeError:
            pass

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    with pytest.raises(ReplayError, match=r"pipe\.jsonl is larger than"):
        load_recording(str(path))
    writer.join(timeout=DEADLINE)
    assert not writer.is_alive()
    assert len(written) < 10_000


# ------------------------------------------------------------ the answers


def test_hold_keeps_answering_the_last() -> None:
    controller = ReplayController(recorded(frames(*I10)), "hold")
    assert [ask(controller, "GET:RC8:10:I:") for _ in range(5)] == [
        b"0,3,1\r",
        b"0,3,2\r",
        b"0,3,3\r",
        b"0,3,3\r",
        b"0,3,3\r",
    ]


def test_cycle_starts_again_from_the_first() -> None:
    controller = ReplayController(recorded(frames(*I10)), "cycle")
    replies = [ask(controller, "GET:RC8:10:I:") for _ in range(7)]
    assert replies == [b"0,3,1\r", b"0,3,2\r", b"0,3,3\r"] * 2 + [b"0,3,1\r"]


def test_hold_is_the_default() -> None:
    assert ReplayController(recorded(frames(I10[0]))).end == "hold"
    with pytest.raises(ValueError):
        ReplayController(recorded(frames(I10[0])), "loop")


def test_variables_keep_their_own_place() -> None:
    controller = ReplayController(recorded(frames(*I10, ("GET:RC8:0:F:", "0,4,1.5"))))
    assert ask(controller, "GET:RC8:10:I:") == b"0,3,1\r"
    assert ask(controller, "GET:RC8:0:F:") == b"0,4,1.5\r"
    assert ask(controller, "GET:RC8:10:I:") == b"0,3,2\r"


def test_unrecorded_puts_and_bad_lines_get_errors_and_notices() -> None:
    told: list[tuple[str, str]] = []
    controller = ReplayController(
        recorded(frames(*I10, ("GET:RC8:500:I:", "-2147024809"))), notify=lambda *n: told.append(n)
    )
    assert code(ask(controller, "GET:RC8:11:I:")) == E_NOTIMPL
    assert code(ask(controller, "GET:RC8:11:I:")) == E_NOTIMPL
    assert code(ask(controller, "GET:RC8:10:F:")) == E_NOTIMPL
    assert code(ask(controller, "PUT:RC8:10:I:3,5")) == E_ACCESSDENIED
    assert code(ask(controller, "GET:RC8:500:I:")) == E_INVALIDARG  # as it was recorded
    assert code(ask(controller, "PUT:RC8:10:11,0")) == E_INVALIDCOMMAND  # as an RC8 reads it
    assert code(ask(controller, "GET:RC8:10:I:3,1")) == E_INVALIDCOMMAND
    assert code(ask(controller, "HELLO")) == E_INVALIDCOMMAND
    assert code(controller.handle(b"GET:RC8:10:\xff:")[0]) == E_INVALIDCOMMAND
    reply, close = controller.handle(b"GET:RC8:10:I:" + b" " * 300)
    assert code(reply) == E_INVALIDRCVPACKET and close
    # A PUT changed nothing: the recorded answers go on from the first.
    assert ask(controller, "GET:RC8:10:I:") == b"0,3,1\r"
    assert told == [
        ("replay-unrecorded", "replay: GET:RC8:11:I: not in the recording: answered E_NOTIMPL"),
        ("replay-unrecorded", "replay: GET:RC8:10:F: not in the recording: answered E_NOTIMPL"),
        ("replay-put", "replay: PUT:RC8:10:I: refused (E_ACCESSDENIED): a replay is read-only"),
    ]
    assert controller.known_frames == {}  # nothing for the server's fast path to keep


def test_the_end_is_told_once_per_variable() -> None:
    told: list[tuple[str, str]] = []
    controller = ReplayController(recorded(frames(*I10)), "cycle", notify=lambda *n: told.append(n))
    for _ in range(9):
        ask(controller, "GET:RC8:10:I:")
    assert told == [
        (
            "replay-end",
            "replay: GET:RC8:10:I: past its 3 recorded answers: starting again from the first",
        )
    ]


# ---------------------------------------------------------- over the server


async def _ask_all(sim: SimulatorServer, data: list[bytes]) -> list[bytes]:
    """Each item of ``data`` as a write of its own; every reply line read after it."""
    reader, writer = await asyncio.open_connection(sim.host, sim.port)
    replies: list[bytes] = []
    try:
        for chunk in data:
            writer.write(chunk)
            for _ in range(chunk.count(b"\r")):
                replies.append(await asyncio.wait_for(reader.readuntil(b"\r"), DEADLINE))
    finally:
        writer.close()
    return replies


@pytest.mark.parametrize("faults", [{}, {"delay_ms": 1.0}], ids=["fast-path", "fault-path"])
def test_the_server_never_keeps_a_replay_answer(faults: dict[str, float]) -> None:
    """The simulator keeps replies by line for its fast path: a replay's change every time."""
    controller = ReplayController(recorded(frames(*I10)), "cycle")
    line = b"GET:RC8:10:I:\r"

    async def scenario() -> list[bytes]:
        server = SimulatorServer(controller=controller, faults=FaultSettings(**faults))  # type: ignore[arg-type]
        async with server as sim:
            one_by_one = await _ask_all(sim, [line] * 4)
            together = await _ask_all(sim, [line * 3])  # one read holding three requests
            control = await _ask_all(sim, [b"SIM:GET:\r", line])
            return one_by_one + together + control

    replies = asyncio.run(scenario())
    cycle = [b"0,3,1\r", b"0,3,2\r", b"0,3,3\r"]
    assert replies[:7] == [*cycle, *cycle, cycle[0]]
    assert replies[7].startswith(b"0,8,")  # the control lines still work
    assert replies[8] == b"0,3,2\r"
    assert controller.requests == 8  # the SIM: line is the server's, not a request


def test_the_simulator_itself_still_keeps_its_replies() -> None:
    """The shared request reader changed nothing for the simulator."""
    controller = SimulatedController()
    assert controller.handle(b"get:rc8:010:i:") == (b"0,3,0\r", False)
    assert controller.handle(b"  GET:RC8:10:I:") == (b"0,3,0\r", False)
    assert controller.handle(b"GET:RC8:10:X:")[0] == b"-2147418107\r"
    assert controller.handle(b"GET:RC8:100:I:")[0] == b"-2147024809\r"
    assert controller.known_frames
