"""``get ... -r N -i S`` and ``watch VAR...``: the real CLI as a subprocess, against the
built-in simulator and servers written here (127.0.0.1 port 0), read as a pipe reads it.
"""

from __future__ import annotations

import csv
import itertools
import json
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from datetime import datetime
from pathlib import Path
from typing import ClassVar

import pytest

from tests.support import drivers as shared
from tests.support.drivers import cli, json_lines
from tests.support.servers import CLOSE, RecordingServer, fixed_reply, unused_port

pytestmark = pytest.mark.slow


STAMP_RE = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}[+-]\d\d:\d\d")
E_INVALIDARG = b"-2147024809\r"
POSIX_ONLY = pytest.mark.skipif(
    sys.platform == "win32", reason="Windows cannot send SIGINT to one process"
)


def stamp(text: str) -> datetime:
    """An ISO 8601 time with milliseconds and the UTC offset."""
    assert STAMP_RE.fullmatch(text), text
    return datetime.fromisoformat(text)


def gaps(times: list[str]) -> list[float]:
    moments = [stamp(t) for t in times]
    return [(b - a).total_seconds() for a, b in itertools.pairwise(moments)]


def two_apart(times: list[str]) -> list[float]:
    """Seconds from each line's time to the time two lines later. A line's time is its
    cycle's end, which a busy machine delays by any amount, so two neighbours may come
    closer than the interval; but a cycle starts only after the one before has ended and
    an interval after that one's start, so the cycle two later ends at least an interval
    after the first (less a millisecond of rounding): a bound, whatever the load."""
    moments = [stamp(t) for t in times]
    return [(b - a).total_seconds() for a, b in zip(moments, moments[2:], strict=False)]


def no_traceback(stderr: str) -> None:
    assert "Traceback" not in stderr
    assert "Exception ignored" not in stderr
    assert "BrokenPipe" not in stderr


def answer_by_line(answers: dict[bytes, bytes | object]) -> Callable[[bytes], object]:
    """Answers per request line; any other line closes the connection."""
    return lambda line: answers.get(line, CLOSE)


def _default_sigint() -> None:
    """In the child, between fork and exec: SIGINT back to its default, so the child
    takes Ctrl-C as from a terminal even when the tests run with SIGINT ignored (a
    background job, nohup), which a child would otherwise inherit."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


#: How long a subprocess has to finish what the test waits for: never a figure the
#: test checks, only the point where a hung child is called a failure.
DEADLINE = 20.0


class Running:
    """The CLI as a running subprocess; its stdout lines arrive in a queue as printed.

    With ``keep=N`` the reader takes N lines and then closes its end of the pipe, as
    ``| head -N`` does. Every wait on it has a deadline; whatever a test leaves running
    is killed when the test ends (the ``_no_process_left`` fixture).
    """

    started: ClassVar[list[Running]] = []

    def __init__(self, env: dict[str, str], tmp_path: Path, *args: str, keep: int = 0) -> None:
        self._stderr_path = tmp_path / f"stderr-{id(self)}.txt"
        self._stderr = self._stderr_path.open("w", encoding="utf-8")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "rac_console", *args],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            text=True,
            encoding="utf-8",
            preexec_fn=None if sys.platform == "win32" else _default_sigint,
        )
        Running.started.append(self)
        self.lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._read, args=(keep,), daemon=True).start()

    def _read(self, keep: int) -> None:
        stdout = self.process.stdout
        assert stdout is not None
        for number, line in enumerate(stdout, 1):
            self.lines.put(line)
            if number == keep:
                stdout.close()  # the reader goes away, as head does
                return
        self.lines.put(None)

    def _next(self, deadline: float, what: str) -> str | None:
        left = deadline - time.monotonic()
        try:
            if left <= 0:
                raise queue.Empty
            return self.lines.get(timeout=left)
        except queue.Empty:
            raise AssertionError(f"{what}; stderr: {self.stderr()}") from None

    def line(self, timeout: float = DEADLINE) -> str:
        line = self._next(time.monotonic() + timeout, f"no line within {timeout} s")
        assert line is not None, f"stdout ended; stderr: {self.stderr()}"
        return line

    def rest(self, timeout: float = DEADLINE) -> list[str]:
        """The lines still to come, up to the end of stdout, which must come within
        ``timeout`` (a watch that never took its SIGINT would print for ever)."""
        deadline = time.monotonic() + timeout
        lines = []
        while (line := self._next(deadline, f"stdout did not end within {timeout} s")) is not None:
            lines.append(line)
        return lines

    def finish(self, timeout: float = DEADLINE) -> int:
        try:
            return self.process.wait(timeout=timeout)
        finally:
            self.stop()

    def stop(self) -> None:
        """Kill it if it still runs; close what the test held open."""
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(timeout=DEADLINE)
        self._stderr.close()

    def stderr(self) -> str:
        return self._stderr_path.read_text(encoding="utf-8")


@pytest.fixture(autouse=True)
def _no_process_left() -> Iterator[None]:
    """A test that failed half way leaves no CLI running behind it."""
    yield
    while Running.started:
        Running.started.pop().stop()


# ------------------------------------------------------------------ get -r N -i S


def test_get_repeats_as_json_lines_with_repetition_and_time(env: dict[str, str]) -> None:
    result = cli(env, "get", "I", "0", "-r", "3", "-i", "0", "--json")
    assert result.returncode == 0, result.stderr
    data = json_lines(result.stdout)
    assert [d["repetition"] for d in data] == [1, 2, 3]
    assert all(d["ok"] and d["request"] == "GET:RC8:0:I:" for d in data)
    assert all(gap >= 0 for gap in gaps([d["time"] for d in data]))


@pytest.mark.parametrize(
    "words",
    [
        ["get", "-r", "3", "I", "0"],
        ["get", "I", "0", "-r", "3", "-i", "0"],
        ["get", "I0", "--repeat=3", "--interval=0"],
        ["-r", "3", "get", "I", "0"],  # before the command: refused below
    ],
)
def test_repeat_options_may_stand_before_or_after_the_variable(
    env: dict[str, str], words: list[str]
) -> None:
    result = cli(env, "--json", *words)
    if words[0] != "get":
        assert result.returncode == 2  # -r is get's, not a global option
        return
    assert result.returncode == 0, result.stderr
    assert [d["repetition"] for d in json_lines(result.stdout)] == [1, 2, 3]


def test_the_moving_counter_moves_across_repetitions(env: dict[str, str]) -> None:
    # I0 is the simulator's 10 Hz cycle counter: 0.2 s apart, every read is higher.
    result = cli(env, "--json", "get", "I", "0", "-r", "3", "-i", "0.2")
    assert result.returncode == 0, result.stderr
    values = [d["value"] for d in json_lines(result.stdout)]
    assert values == sorted(set(values)), values


def test_the_interval_spaces_the_repetitions(env: dict[str, str]) -> None:
    """A smoke test: the CLI follows the schedule (start to start, pinned by
    test_live_schedule.py on a clock of its own)."""
    result = cli(env, "--json", "get", "I", "0", "-r", "4", "-i", "0.25")
    assert result.returncode == 0, result.stderr
    spans = two_apart([d["time"] for d in json_lines(result.stdout)])
    assert len(spans) == 2 and all(span >= 0.24 for span in spans), spans


def test_get_repeated_as_text_is_time_tab_and_what_get_prints(env: dict[str, str]) -> None:
    result = cli(env, "get", "I", "2", "-r", "2")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 2
    for line in lines:
        time_text, shown = line.split("\t")
        stamp(time_text)
        assert shown.split()[:3] == ["I2", "=", "250"]


def test_repeated_errors_give_exit_1_and_a_line_each(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording(fixed_reply(E_INVALIDARG))
    result = cli(env, *server.args, "get", "I", "10", "-r", "3")
    assert result.returncode == 1
    assert result.stdout == ""
    errors = result.stderr.splitlines()
    assert [e.split(" at ")[0] for e in errors] == [
        f"rac-console: repetition {n}" for n in (1, 2, 3)
    ]
    assert all("E_INVALIDARG" in e for e in errors)

    result = cli(env, *server.args, "--json", "get", "I", "10", "-r", "2")
    assert result.returncode == 1
    assert [(d["repetition"], d["result_name"]) for d in json_lines(result.stdout)] == [
        (1, "E_INVALIDARG"),
        (2, "E_INVALIDARG"),
    ]


def test_a_closed_connection_is_exit_3_and_every_repetition_is_tried(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording(fixed_reply(CLOSE))
    result = cli(env, *server.args, "--json", "get", "I", "10", "-r", "2", "-i", "0")
    assert result.returncode == 3
    data = json_lines(result.stdout)
    assert [(d["repetition"], d["ok"]) for d in data] == [(1, False), (2, False)]
    assert server.lines == [b"GET:RC8:10:I:"] * 2


# --------------------------------------------------------------------- watch


def test_watch_json_has_every_variable_each_cycle(env: dict[str, str]) -> None:
    result = cli(env, "watch", "I", "1", "IO", "128-131", "--count", "3", "--json")
    assert result.returncode == 0, result.stderr
    data = json_lines(result.stdout)
    assert [d["cycle"] for d in data] == [1, 2, 3]
    for cycle in data:
        stamp(cycle["time"])
        assert list(cycle["values"]) == ["I1", "IO128", "IO129", "IO130", "IO131"]
        assert cycle["values"]["I1"] == 1
        assert all(isinstance(cycle["values"][f"IO{n}"], bool) for n in range(128, 132))
        assert (cycle["ok"], cycle["errors"]) == (True, {})


def test_watch_text_is_time_then_tab_separated_name_value_fields(env: dict[str, str]) -> None:
    result = cli(env, "watch", "I", "1", "IO", "128-129", "P", "0", "--count", "2", "--every", "0")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 2
    for line in lines:
        time_text, *fields = line.split("\t")
        stamp(time_text)
        pairs = [field.split("=", 1) for field in fields]
        assert [name for name, _ in pairs] == ["I1", "IO128", "IO129", "P0"]
        values = dict(pairs)
        assert values["I1"] == "1"
        assert {values["IO128"], values["IO129"]} <= {"ON", "OFF"}
        assert len([float(v) for v in values["P0"].split(",")]) == 7


def test_watch_cycles_are_spaced_by_every(env: dict[str, str]) -> None:
    """A smoke test, as for get -r: the schedule itself is test_live_schedule.py's."""
    result = cli(env, "--json", "watch", "P", "0", "J", "0", "--every", "0.25", "--count", "4")
    assert result.returncode == 0, result.stderr
    spans = two_apart([d["time"] for d in json_lines(result.stdout)])
    assert len(spans) == 2 and all(span >= 0.24 for span in spans), spans


def test_watch_shows_wire_text_escaped(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording(fixed_reply(b"0,8,red\x1b[31m\r"))
    result = cli(env, *server.args, "watch", "S", "1", "--count", "1")
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\t")[1] == "S1=red\\x1b[31m\n"


def test_a_controller_error_is_in_the_line_and_exit_1(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    ok = b"0,3,7\r"
    server = recording(answer_by_line({b"GET:RC8:1:I:": ok, b"GET:RC8:10:I:": E_INVALIDARG}))
    result = cli(env, *server.args, "watch", "I", "1", "I", "10", "--count", "3", "--every", "0")
    assert result.returncode == 1
    lines = result.stdout.splitlines()
    assert [line.split("\t")[1:] for line in lines] == [["I1=7", "I10=!E_INVALIDARG"]] * 3
    (said,) = result.stderr.splitlines()  # once, not every cycle
    assert said.startswith("rac-console: I10: ") and "E_INVALIDARG" in said

    result = cli(env, *server.args, "--json", "watch", "I", "1", "I10", "--count", "1")
    (cycle,) = json_lines(result.stdout)
    assert cycle["ok"] is False
    assert cycle["values"] == {"I1": 7, "I10": None}
    assert list(cycle["errors"]) == ["I10"] and "E_INVALIDARG" in cycle["errors"]["I10"]


@pytest.mark.parametrize(
    ("reply", "reason"),
    [(CLOSE, "disconnected"), (None, "timeout"), ("refused", "no-connection")],
)
def test_a_failing_connection_is_exit_3_and_count_still_ends_it(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
    reply: object,
    reason: str,
) -> None:
    """Every cycle tries again; the variables after the failure are skipped."""
    server = recording(answer_by_line({b"GET:RC8:1:I:": b"0,3,7\r", b"GET:RC8:2:I:": reply}))
    target = server.args if reply != "refused" else ["-H", "127.0.0.1", "-p", str(unused_port())]
    words = ["watch", "I", "1", "I", "2", "I", "3", "--count", "3", "--every", "0"]
    result = cli(env, *target, "--timeout", "0.3", *words)
    assert result.returncode == 3
    no_traceback(result.stderr)
    lines = [line.split("\t")[1:] for line in result.stdout.splitlines()]
    first = "I1=!no-connection" if reply == "refused" else "I1=7"
    second = "I2=!skipped" if reply == "refused" else f"I2=!{reason}"
    assert lines == [[first, second, "I3=!skipped"]] * 3

    result = cli(env, *target, "--timeout", "0.3", "--json", *words[:-4], "--count", "1")
    (cycle,) = json_lines(result.stdout)
    assert cycle["values"]["I3"] is None
    assert "not read" in cycle["errors"]["I3"]


# -------------------------------------------------------------- pipes and Ctrl-C


@pytest.mark.parametrize(
    "words",
    [
        ["watch", "I", "0", "--every", "0.01"],
        ["--json", "watch", "I", "0", "IO", "0-7", "--every", "0"],
        ["get", "I", "0", "-r", "100000", "-i", "0.01"],
        ["--json", "get", "I", "0", "-r", "100000"],
    ],
)
def test_a_closed_pipe_ends_it_quietly(
    env: dict[str, str], tmp_path: Path, words: list[str]
) -> None:
    running = Running(env, tmp_path, *words, keep=1)
    running.line()
    assert running.finish() == 0
    no_traceback(running.stderr())


@POSIX_ONLY
def test_ctrl_c_ends_watch_with_its_lines_and_exit_0(env: dict[str, str], tmp_path: Path) -> None:
    running = Running(env, tmp_path, "--json", "watch", "I", "0", "P", "0", "--every", "0.05")
    seen = [running.line(), running.line()]
    running.process.send_signal(signal.SIGINT)
    seen += running.rest()
    assert running.finish() == 0
    no_traceback(running.stderr())
    assert "interrupted" not in running.stderr()
    cycles = [json.loads(line) for line in seen]  # every line whole
    assert [c["cycle"] for c in cycles] == list(range(1, len(cycles) + 1))


@POSIX_ONLY
def test_ctrl_c_ends_watch_with_the_worst_status_seen(
    env: dict[str, str], tmp_path: Path, recording: Callable[..., RecordingServer]
) -> None:
    server = recording(fixed_reply(E_INVALIDARG))
    running = Running(env, tmp_path, *server.args, "watch", "I", "10", "--every", "0.05")
    running.line()
    running.process.send_signal(signal.SIGINT)
    running.rest()
    assert running.finish() == 1


@POSIX_ONLY
def test_ctrl_c_cuts_a_repeated_get_short_with_130(env: dict[str, str], tmp_path: Path) -> None:
    running = Running(env, tmp_path, "get", "I", "0", "-r", "1000", "-i", "0.05")
    running.line()
    running.process.send_signal(signal.SIGINT)
    running.rest()
    assert running.finish() == 130
    assert "interrupted" in running.stderr()
    no_traceback(running.stderr())


# ------------------------------------------------------------- watch --log-csv


def csv_rows(path: Path) -> list[list[str]]:
    with path.open(encoding="utf-8", newline="") as handle:
        return list(csv.reader(handle))


@pytest.mark.parametrize("before", [True, False], ids=["option-first", "option-last"])
def test_watch_logs_each_cycle_as_a_csv_row(
    env: dict[str, str], tmp_path: Path, before: bool
) -> None:
    log = tmp_path / "watch.csv"
    words = ["watch", "I", "1", "IO", "128-129", "P", "0", "--count", "3", "--every", "0"]
    option = ["--log-csv", str(log)]
    result = cli(env, "--json", *(option + words if before else words + option))
    assert result.returncode == 0, result.stderr
    header, *rows = csv_rows(log)
    assert header[:4] == ["time", "I1", "IO128", "IO129"]
    assert header[4:] == [f"P0.{label}" for label in ("X", "Y", "Z", "Rx", "Ry", "Rz", "Fig")]
    assert len(rows) == 3
    for row, cycle in zip(rows, json_lines(result.stdout), strict=True):
        stamp(row[0])
        values = cycle["values"]
        assert row[1:4] == ["1", str(int(values["IO128"])), str(int(values["IO129"]))]
        assert [float(cell) for cell in row[4:]] == pytest.approx(values["P0"])


def test_the_csv_log_appends_and_leaves_a_failed_read_empty(
    env: dict[str, str], tmp_path: Path, recording: Callable[..., RecordingServer]
) -> None:
    server = recording(
        answer_by_line({b"GET:RC8:1:I:": b"0,3,7\r", b"GET:RC8:10:I:": E_INVALIDARG})
    )
    log = tmp_path / "watch.csv"
    words = ["watch", "I", "1", "I", "10", "--every", "0", "--log-csv", str(log)]
    assert cli(env, *server.args, *words, "--count", "2").returncode == 1
    assert cli(env, *server.args, *words, "--count", "1").returncode == 1
    header, *rows = csv_rows(log)
    assert header == ["time", "I1", "I10"]  # once: the second run appended
    assert [row[1:] for row in rows] == [["7", ""]] * 3


def test_a_csv_log_with_other_columns_is_refused_before_sending(
    env: dict[str, str], tmp_path: Path, recording: Callable[..., RecordingServer]
) -> None:
    server = recording(fixed_reply(b"0,3,1\r"))
    log = tmp_path / "watch.csv"
    log.write_text("time,I2\r\n", encoding="utf-8")
    result = cli(env, *server.args, "watch", "I", "1", "--count", "1", "--log-csv", str(log))
    assert result.returncode == 2
    assert str(log) in shared.one_error_line(result)  # why is csvlog's to say
    assert server.connections() == []
    assert log.read_bytes() == b"time,I2\r\n"


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full, a full disk")
def test_a_failing_csv_log_is_said_once_and_exit_4(env: dict[str, str]) -> None:
    words = ["watch", "I", "1", "--count", "3", "--every", "0", "--log-csv", "/dev/full"]
    result = cli(env, "--json", *words)
    assert result.returncode == 4
    assert len(json_lines(result.stdout)) == 3  # the watch went on
    said = [line for line in result.stderr.splitlines() if "/dev/full" in line]
    assert len(said) == 1, result.stderr
    no_traceback(result.stderr)


@pytest.mark.parametrize(
    "words",
    [
        ["get", "I", "0", "-r", "2"],
        ["get", "I", "0"],
        ["--json", "put", "I", "0", "5"],
        ["run", "-"],
        ["latency", "--count", "2"],
    ],
)
def test_log_csv_with_another_command_is_refused(
    env: dict[str, str],
    tmp_path: Path,
    recording: Callable[..., RecordingServer],
    words: list[str],
) -> None:
    server = recording(fixed_reply(b"0,3,1\r"))
    log = tmp_path / "ignored.csv"
    result = cli(env, *server.args, "--log-csv", str(log), *words, stdin="get I 0\n")
    assert result.returncode == 2
    assert "rac-console watch" in shared.one_error_line(result)
    assert result.stdout == ""
    assert server.connections() == []
    assert not log.exists()


# ----------------------------------------------------------- a closed stderr


def with_stderr_closed(env: dict[str, str], *args: str) -> subprocess.CompletedProcess[str]:
    """The CLI with stderr a pipe whose reader has gone before it starts: every write
    to stderr fails (EPIPE), as with ``2> >(head -c 0)``."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        return subprocess.run(
            [sys.executable, "-m", "rac_console", *args],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=write_end,
            text=True,
            encoding="utf-8",
            timeout=20,
        )
    finally:
        os.close(write_end)


def test_a_closed_stderr_keeps_the_status_of_a_repeated_get(env: dict[str, str]) -> None:
    refused = ["-H", "127.0.0.1", "-p", str(unused_port())]
    result = with_stderr_closed(env, *refused, "--json", "get", "I", "0", "-r", "2")
    assert result.returncode == 3
    assert [(d["repetition"], d["ok"]) for d in json_lines(result.stdout)] == [
        (1, False),
        (2, False),
    ]
    result = with_stderr_closed(env, *refused, "get", "I", "0", "-r", "2")
    assert (result.returncode, result.stdout) == (3, "")


def test_a_closed_stderr_leaves_the_lines_on_stdout(env: dict[str, str]) -> None:
    """The built-in simulator's notice goes to stderr first: its failure must not end
    the watch or take stdout with it."""
    result = with_stderr_closed(env, "watch", "I", "1", "--count", "2", "--every", "0")
    assert result.returncode == 0
    assert [line.split("\t")[1] for line in result.stdout.splitlines()] == ["I1=1"] * 2

    result = with_stderr_closed(env, "watch", "Q", "0")  # refused: said on stderr
    assert result.returncode == 2


# ------------------------------------------------------ refused before sending


@pytest.mark.parametrize(
    ("words", "said"),
    [
        (["get", "I", "0", "-r", "x"], "-r/--repeat"),
        (["get", "I", "0", "-r", "0"], "use watch"),
        (["get", "I", "0", "-r", "-2"], "-r/--repeat"),
        (["get", "I", "0", "-r", "3", "-i", "-1"], "-i/--interval"),
        (["get", "I", "0", "-r", "3", "-i", "x"], "-i/--interval"),
        (["get", "I", "0", "-i", "0.5"], "-i needs -r N"),
        (["get", "I", "0", "-r"], "-r needs a value"),
        (["put", "I", "10", "5", "-r", "3"], "looks like an option"),
        (["send", "GET:RC8:10:I:", "-r", "3"], "looks like an option"),
        (["watch", "I", "0", "--every", "-1"], "--every"),
        (["watch", "I", "0", "--every", "x"], "--every"),
        (["watch", "I", "0", "--count", "0"], "leave --count out"),
        (["watch", "I", "0", "--count", "x"], "--count"),
        (["watch", "I", "0", "every", "0.2"], "--every 0.2"),
        (["watch", "I", "0", "gripper"], "variables only"),
        (["watch", "Q", "0"], "unknown variable type"),
        (["watch", "IO", "9-3"], "range runs upwards"),
    ],
)
def test_bad_values_exit_2_and_send_nothing(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
    words: list[str],
    said: str,
) -> None:
    server = recording(fixed_reply(b"0,3,1\r"))
    result = cli(env, *server.args, *words)
    assert result.returncode == 2
    no_traceback(result.stderr)
    assert said in result.stderr
    assert server.connections() == []
    assert server.received == b""
