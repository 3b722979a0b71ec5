"""``rac-console sim --replay FILE`` as a user runs it: a file recorded by the real CLI
against the built-in simulator, replayed by a ``rac-console sim`` subprocess on
127.0.0.1 port 0, read back by the real CLI.

HOME and the XDG directories point into a temporary directory. Every wait has a
deadline; nothing sleeps and hopes.
"""

from __future__ import annotations

import json
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import cast

import pytest

from rac_console.sim.replay import MAX_FILE_BYTES, MAX_LINE_BYTES
from tests.support.drivers import cli

pytestmark = pytest.mark.slow

DEADLINE = 15.0
SIM = [sys.executable, "-m", "rac_console", "sim"]
LISTENING = "RC8 simulator listening on 127.0.0.1:"
#: Recorded at the "cell" (the built-in simulator): I10 moves 1, 2, 3; S1 and an error.
SESSION = "put I 10 1\nget I 10\nput I 10 2\nget I 10\nput I 10 3\nget I 10\nget S 1\nget I 500\n"


class Replay:
    """A running ``rac-console sim --replay``: its port, and its stderr line by line."""

    def __init__(self, process: subprocess.Popen[str]) -> None:
        self.process = process
        self.stdout: queue.Queue[str] = queue.Queue()
        self.stderr: queue.Queue[str] = queue.Queue()
        self.said: list[str] = []  # stderr lines read so far
        for stream, lines in ((process.stdout, self.stdout), (process.stderr, self.stderr)):
            threading.Thread(target=_pump, args=(stream, lines), daemon=True).start()
        line = self.stdout.get(timeout=DEADLINE)
        assert line.startswith(LISTENING), line
        self.port = int(line[len(LISTENING) :].split()[0])

    def wait_for_stderr(self, found: Callable[[str], bool]) -> str:
        """The first stderr line (read so far or yet to come) for which ``found`` holds."""
        deadline = time.monotonic() + DEADLINE
        for line in self.said:
            if found(line):
                return line
        while True:
            left = deadline - time.monotonic()
            assert left > 0, f"not said on stderr; said: {self.said}"
            try:
                line = self.stderr.get(timeout=left)
            except queue.Empty:
                continue
            self.said.append(line)
            if found(line):
                return line


def _pump(stream, lines: queue.Queue[str]) -> None:
    for line in stream:
        lines.put(line)


@pytest.fixture
def replay(env: dict[str, str]) -> Iterator[Callable[..., Replay]]:
    processes: list[subprocess.Popen[str]] = []

    def start(path: Path, *options: str) -> Replay:
        process = subprocess.Popen(
            [*SIM, "--port", "0", "--replay", str(path), *options],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            encoding="utf-8",
            errors="backslashreplace",
        )
        processes.append(process)
        return Replay(process)

    yield start
    for process in processes:
        process.terminate()
        try:
            process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=5)
        for stream in (process.stdout, process.stderr):
            if stream is not None:
                stream.close()


@pytest.fixture
def recorded(env: dict[str, str], tmp_path: Path) -> Path:
    """A record file written by the real CLI: two runs, appended to one file."""
    path = tmp_path / "cell.jsonl"
    result = cli(env, "--record", str(path), "--no-verify", "run", "-", stdin=SESSION)
    assert result.returncode == 1, result.stderr  # get I 500: the controller's error
    result = cli(env, "--record", str(path), "get", "P", "1")
    assert result.returncode == 0, result.stderr
    return path


def get(env: dict[str, str], port: int, *variable: str) -> dict[str, object]:
    result = cli(env, "-H", "127.0.0.1", "-p", str(port), "--json", "get", *variable)
    assert "Traceback" not in result.stderr
    (data,) = [json.loads(line) for line in result.stdout.splitlines() if line.strip()]
    return cast(dict[str, object], data)


# ------------------------------------------------------------------ replaying


def test_gets_answer_the_recorded_values_in_order_then_hold(
    env: dict[str, str], recorded: Path, replay: Callable[..., Replay]
) -> None:
    server = replay(recorded)
    started = server.wait_for_stderr(lambda line: "replaying" in line)
    assert "cell.jsonl: 4 variables, 6 answers" in started
    assert "hold the last" in started

    values = [get(env, server.port, "I", "10")["value"] for _ in range(5)]
    assert values == [1, 2, 3, 3, 3]  # the simulator's own I10 is 0
    assert get(env, server.port, "S", "1")["value"] == "RC8 simulator"
    assert get(env, server.port, "P", "1")["value"] == [350, 0, 450, 180, 0, 180, 5]
    error = get(env, server.port, "I", "500")
    assert (error["ok"], error["result_name"]) == (False, "E_INVALIDARG")  # as recorded
    server.wait_for_stderr(lambda line: "GET:RC8:10:I: past its 3 recorded answers" in line)


def test_cycle_starts_each_variable_again(
    env: dict[str, str], recorded: Path, replay: Callable[..., Replay]
) -> None:
    server = replay(recorded, "--replay-end", "cycle")
    assert "start again from the first" in server.wait_for_stderr(lambda s: "replaying" in s)
    values = [get(env, server.port, "I10")["value"] for _ in range(7)]
    assert values == [1, 2, 3, 1, 2, 3, 1]


def test_unrecorded_gets_and_puts_get_errors(
    env: dict[str, str], recorded: Path, replay: Callable[..., Replay]
) -> None:
    server = replay(recorded)
    unknown = get(env, server.port, "I", "11")
    assert (unknown["ok"], unknown["result_name"], unknown["value"]) == (False, "E_NOTIMPL", None)
    server.wait_for_stderr(lambda line: "GET:RC8:11:I: not in the recording" in line)

    target = ("-H", "127.0.0.1", "-p", str(server.port))
    result = cli(env, *target, "--json", "--no-verify", "put", "I", "10", "7")  # no GETs
    assert result.returncode == 1
    (put,) = [json.loads(line) for line in result.stdout.splitlines()]
    assert put["result_name"] == "E_ACCESSDENIED"
    server.wait_for_stderr(lambda line: "read-only" in line)
    assert get(env, server.port, "I", "10")["value"] == 1  # the PUT changed nothing


def test_recorded_escape_sequences_never_reach_a_terminal_raw(
    env: dict[str, str], tmp_path: Path, replay: Callable[..., Replay]
) -> None:
    path = tmp_path / "evil.jsonl"
    records = [
        {"dir": "tx", "text": "GET:RC8:1:S:"},
        {"dir": "rx", "text": "0,8,\\x1b]0;owned\\x07\\x1b[2Jred", "rtt_ms": 1.0},
    ]
    path.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    server = replay(path)
    result = cli(env, "-H", "127.0.0.1", "-p", str(server.port), "get", "S", "1")
    assert result.returncode == 0, result.stderr
    assert "red" in result.stdout
    get(env, server.port, "S", "1")  # past the end: said on the replay's stderr
    server.wait_for_stderr(lambda line: "past its 1 recorded answers" in line)
    for text in (result.stdout, result.stderr, *server.said):
        assert "\x1b" not in text and "\x07" not in text


# ------------------------------------------------------- files it cannot serve


def one_error_line(result: subprocess.CompletedProcess[str]) -> str:
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip("\n").split("\n")
    assert len(lines) == 1, result.stderr
    assert "listening" not in result.stdout
    return lines[0]


def serve(env: dict[str, str], *args: str) -> subprocess.CompletedProcess[str]:
    return cli(env, "sim", "--port", "0", *args)


def test_a_malformed_file_is_one_line_naming_the_line(
    env: dict[str, str], recorded: Path, tmp_path: Path
) -> None:
    path = tmp_path / "broken.jsonl"
    lines = recorded.read_text(encoding="utf-8").splitlines()
    path.write_text("\n".join([*lines[:2], "{not json", *lines[2:]]) + "\n", encoding="utf-8")
    line = one_error_line(serve(env, "--replay", str(path)))
    assert line == f"rac-console: {path} line 3 is not JSON (not a --record file?)"

    path.write_text('{"dir": "\\u001b[2J", "text": ""}\n', encoding="utf-8")
    line = one_error_line(serve(env, "--replay", str(path)))
    assert "line 1: 'dir' must be" in line
    assert "\x1b" not in line


def test_missing_empty_and_useless_files_exit_2(env: dict[str, str], tmp_path: Path) -> None:
    assert "cannot read the replay file" in one_error_line(
        serve(env, "--replay", str(tmp_path / "nope.jsonl"))
    )
    empty = tmp_path / "empty.jsonl"
    empty.write_text("", encoding="utf-8")
    assert "nothing to replay" in one_error_line(serve(env, "--replay", str(empty)))
    puts = tmp_path / "puts.jsonl"
    puts.write_text(
        '{"dir": "tx", "text": "PUT:RC8:1:I:3,1"}\n{"dir": "rx", "text": "0"}\n', encoding="utf-8"
    )
    assert "nothing to replay" in one_error_line(serve(env, "--replay", str(puts)))
    assert "--replay-end needs --replay" in one_error_line(serve(env, "--replay-end", "cycle"))


#: One answered GET as --record writes it (two lines).
PAIR = (
    '{"t": 1712345678.123456, "dir": "tx", "text": "GET:RC8:10:I:"}\n'
    '{"t": 1712345678.124012, "dir": "rx", "text": "0,3,14", "rtt_ms": 0.556}\n'
)


def test_a_line_longer_than_the_limit_is_refused_not_read(
    env: dict[str, str], tmp_path: Path
) -> None:
    path = tmp_path / "long.jsonl"
    head = '{"dir": "rx", "text": "0,8,'
    tail = '"}'
    filler = "A" * (MAX_LINE_BYTES + 1 - len(head) - len(tail))  # one byte over
    path.write_text(PAIR + head + filler + tail + "\n" + PAIR, encoding="ascii")
    line = one_error_line(serve(env, "--replay", str(path)))
    assert line.startswith(f"rac-console: {path} line 3 is longer than ")
    assert f"{MAX_LINE_BYTES // 1024} KiB" in line
    assert "--record" in line
    assert filler[:100] not in line


def test_a_file_larger_than_the_limit_is_refused_not_read(
    env: dict[str, str], tmp_path: Path
) -> None:
    path = tmp_path / "big.jsonl"
    block = PAIR * (1024 * 1024 // len(PAIR))
    with path.open("w", encoding="ascii") as file:
        for _ in range(MAX_FILE_BYTES // len(block)):
            file.write(block)
        file.write(PAIR * ((MAX_FILE_BYTES - file.tell()) // len(PAIR) + 1))  # just over
    assert MAX_FILE_BYTES < path.stat().st_size <= MAX_FILE_BYTES + len(PAIR)
    started = time.monotonic()
    line = one_error_line(serve(env, "--replay", str(path)))
    assert line.startswith(f"rac-console: {path} is larger than ")
    assert f"{MAX_FILE_BYTES // (1024 * 1024)} MiB" in line
    assert "split" in line  # how to replay it anyway
    assert time.monotonic() - started < DEADLINE
