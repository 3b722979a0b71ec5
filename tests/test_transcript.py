"""``--log FILE``: a plain-text timestamped transcript, one line per frame, as tio writes.

The observer alone, then the real CLI as a subprocess (one-shots, ``run -``, a hostile
server whose replies carry escape sequences and C1 bytes), and the console.
"""

from __future__ import annotations

import re
import stat
import sys
import time
from collections.abc import Iterator
from datetime import datetime
from pathlib import Path

import pytest

from rac_console.engine import Engine
from rac_console.engine.files.transcript import FrameTranscript
from rac_console.present.history import History
from rac_console.protocol import InputError
from rac_console.session import Frame
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import cli, results_text, type_line, until
from tests.support.servers import RecordingServer

#: ``[2026-11-22 03:45:55.123] `` then TX, RX or -- (a note).
LINE = re.compile(r"^\[(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d{3})\] (TX|RX|--) (.*)$")

needs_dev_full = pytest.mark.skipif(
    not Path("/dev/full").exists(), reason="a device that is always full (Linux)"
)


def lines_of(path: Path) -> list[tuple[datetime, str, str]]:
    data = path.read_bytes()
    assert all(0x20 <= b < 0x7F or b == 0x0A for b in data), data  # printable ASCII lines
    out = []
    for line in data.decode("ascii").splitlines():
        match = LINE.match(line)
        assert match is not None, line
        when = datetime.strptime(match.group(1), "%Y-%m-%d %H:%M:%S.%f")
        out.append((when, match.group(2), match.group(3)))
    return out


# -------------------------------------------------------------- the observer


def test_each_frame_is_one_line_with_local_time_and_ms(tmp_path: Path) -> None:
    path = tmp_path / "t.log"
    transcript = FrameTranscript(str(path))
    t = time.mktime((2026, 11, 22, 3, 45, 55, 0, 0, -1)) + 0.125  # exact in binary
    transcript(Frame(t, "tx", b"GET:RC8:10:I:\r"))
    transcript(Frame(t + 0.125, "rx", b"0,3,123\r", 0.125))
    transcript(Frame(t + 0.25, "rx", b"0,3,1", unsolicited=True))  # cut off, unasked
    transcript.note("connection lost: \x1b[31mreset", t + 0.375)
    transcript.close()
    assert path.read_text().splitlines() == [
        "[2026-11-22 03:45:55.125] TX GET:RC8:10:I:",
        "[2026-11-22 03:45:55.250] RX 0,3,123",
        "[2026-11-22 03:45:55.375] RX 0,3,1",
        "[2026-11-22 03:45:55.375] -- the line above came with no request waiting",
        "[2026-11-22 03:45:55.375] -- the line above has no CR: the connection closed",
        "[2026-11-22 03:45:55.500] -- connection lost: \\x1b[31mreset",
    ]
    if sys.platform != "win32":  # POSIX modes; Windows has none (see the README)
        assert stat.S_IMODE(path.stat().st_mode) == 0o600


def test_the_file_is_appended_never_truncated(tmp_path: Path) -> None:
    path = tmp_path / "t.log"
    for text in (b"GET:RC8:1:I:\r", b"GET:RC8:2:I:\r"):
        transcript = FrameTranscript(str(path))
        transcript(Frame(time.time(), "tx", text))
        transcript.close()
    assert [line[2] for line in lines_of(path)] == ["GET:RC8:1:I:", "GET:RC8:2:I:"]


def test_bytes_that_are_not_printable_ascii_are_escaped(tmp_path: Path) -> None:
    path = tmp_path / "t.log"
    transcript = FrameTranscript(str(path))
    transcript(Frame(time.time(), "rx", b'0,8,"\x1b[2J\x9b31m\x07a\nb\\"\r', 0.001))
    transcript.close()
    [(_, direction, text)] = lines_of(path)
    assert direction == "RX"
    assert text == '0,8,"\\x1b[2J\\x9b31m\\x07a\\x0ab\\\\"'


def test_an_unwritable_file_is_refused_before_anything(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot write the log file"):
        FrameTranscript(str(tmp_path / "no" / "such" / "dir.log"))


@needs_dev_full
def test_a_failing_disk_is_said_once_and_the_frames_go_on() -> None:
    told: list[str] = []
    transcript = FrameTranscript("/dev/full", told.append)
    for _ in range(3):
        transcript(Frame(time.time(), "tx", b"GET:RC8:1:I:\r"))
    transcript.note("later")
    assert told == [
        "the --log transcript stopped: No space left on device after 0 lines (/dev/full)"
    ]
    assert transcript.failure == told[0]


# ------------------------------------------------------------------ the CLI


@pytest.fixture
def hostile() -> Iterator[RecordingServer]:
    """A server whose replies carry an escape sequence, a C1 CSI byte, BEL and LF."""

    def reply(line: bytes) -> bytes:
        if line.startswith(b"PUT"):
            return b"0\r"
        return b'0,8,"\x1b]0;pwned\x07\x1b[2J\x9b31mred\nnext"\r'

    server = RecordingServer(reply)
    yield server
    server.close()


@pytest.mark.slow
def test_cli_get_writes_a_tx_and_an_rx_line(env: dict[str, str], tmp_path: Path) -> None:
    path = tmp_path / "wire.log"
    before = datetime.now()
    result = cli(env, "--log", str(path), "get", "I", "1")
    assert result.returncode == 0, result.stderr
    lines = lines_of(path)
    assert [(d, t) for _, d, t in lines] == [("TX", "GET:RC8:1:I:"), ("RX", "0,3,1")]
    for when, _, _ in lines:  # local time, as the user's clock says
        assert abs((when - before).total_seconds()) < 20
    assert stat.S_IMODE(path.stat().st_mode) == 0o600


@pytest.mark.slow
def test_cli_run_appends_a_line_per_frame(env: dict[str, str], tmp_path: Path) -> None:
    path = tmp_path / "wire.log"
    path.write_text("[2020-01-01 00:00:00.000] -- kept\n")
    script = "get I 1\nput I 2 7\nsend FOO\nget I 2\n"
    result = cli(env, "--log", str(path), "--no-verify", "run", "--keep-going", "-", stdin=script)
    assert result.returncode == 1, result.stderr  # FOO: E_INVALIDCOMMAND
    lines = lines_of(path)
    assert lines[0][2] == "kept"
    frames = [(d, t) for _, d, t in lines[1:]]
    assert frames[::2] == [
        ("TX", "GET:RC8:1:I:"),
        ("TX", "PUT:RC8:2:I:3,7"),
        ("TX", "FOO"),
        ("TX", "GET:RC8:2:I:"),
    ]
    assert [d for d, _ in frames[1::2]] == ["RX"] * 4
    assert frames[-1] == ("RX", "0,3,7")
    times = [when for when, _, _ in lines[1:]]
    assert times == sorted(times)


@pytest.mark.slow
def test_cli_escapes_what_a_hostile_server_sent(
    env: dict[str, str],
    tmp_path: Path,
    hostile: RecordingServer,
) -> None:
    path = tmp_path / "wire.log"
    result = cli(env, *hostile.args, "--log", str(path), "get", "S", "1")
    assert "Traceback" not in result.stderr
    raw = path.read_bytes()
    assert b"\x1b" not in raw and b"\x9b" not in raw and b"\x07" not in raw
    lines = lines_of(path)
    assert [d for _, d, _ in lines[:2]] == ["TX", "RX"]
    assert lines[1][2] == '0,8,"\\x1b]0;pwned\\x07\\x1b[2J\\x9b31mred\\x0anext"'


@needs_dev_full
@pytest.mark.slow
def test_cli_log_on_a_full_device_is_one_line_and_exit_4(env: dict[str, str]) -> None:
    result = cli(env, "--log", "/dev/full", "run", "-", stdin="get I 1\nget I 2\n")
    assert result.returncode == 4, result.stderr
    errors = [line for line in result.stderr.splitlines() if "simulator" not in line]
    assert errors == [
        "rac-console: the --log transcript stopped: No space left on device after 0 lines "
        "(/dev/full)"
    ]
    assert "I2 = " in result.stdout


@pytest.mark.slow
def test_cli_log_in_a_missing_directory_is_refused(env: dict[str, str], tmp_path: Path) -> None:
    result = cli(env, "--log", str(tmp_path / "no" / "x.log"), "get", "I", "1")
    assert result.returncode == 2
    assert "cannot write the log file" in result.stderr


# ----------------------------------------------------------------- the console


@pytest.mark.slow
async def test_console_log_has_the_typed_frames(tmp_path: Path) -> None:
    path = tmp_path / "console.log"
    engine = Engine(None, timeout=1.0, interval=0.05, transcript=str(path), cycles=True)
    app = RacConsoleApp(engine, History(tmp_path / "history"))
    async with app.run_test(size=(120, 30)) as pilot:
        await type_line(pilot, "get I 3")
        await until(pilot, lambda: "I3 = " in results_text(app), "the result")
    assert ("TX", "GET:RC8:3:I:") in [(d, t) for _, d, t in lines_of(path)]


@needs_dev_full
@pytest.mark.slow
async def test_console_says_a_failing_log_once_and_exits_4(tmp_path: Path) -> None:
    engine = Engine(None, timeout=1.0, interval=0.05, transcript="/dev/full", cycles=True)
    app = RacConsoleApp(engine, History(tmp_path / "history"))
    async with app.run_test(size=(120, 30)) as pilot:
        for n in range(3):
            await type_line(pilot, f"get I {n}")
        await until(pilot, lambda: "I2 = " in results_text(app), "the gets")
        assert results_text(app).count("transcript stopped") == 1
    assert app.exit_status(0) == 4
