"""The real CLI, run as a subprocess, against the built-in simulator, a recording
server (``tests/support/servers.py``), and a ``rac-console sim`` subprocess.

Every server binds 127.0.0.1 port 0; HOME (and the XDG directories) point into
a temporary directory, so nothing here touches the real home directory.
"""

from __future__ import annotations

import json
import queue
import socket
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests.support.drivers import cli, json_lines, one_error_line
from tests.support.servers import RecordingServer, fixed_reply, sample_reply, unused_port

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

JSON_KEYS = {"request", "response", "ok", "result", "result_name", "vt", "value", "rtt_ms"}
E_INVALIDARG = 0x80070057


# ----------------------------------------------- the built-in simulator (no -H)


def test_get_without_host_uses_the_builtin_simulator(env: dict[str, str]) -> None:
    result = cli(env, "get", "I", "2")
    assert result.returncode == 0, result.stderr
    assert result.stdout.split()[:3] == ["I2", "=", "250"]
    assert "VT_I4" in result.stdout
    assert "built-in RC8 simulator" in result.stderr

    result = cli(env, "get", "I", "10")
    assert result.returncode == 0, result.stderr
    assert result.stdout.split()[:3] == ["I10", "=", "0"]


def test_json_put_then_get_p_over_one_session(env: dict[str, str]) -> None:
    script = "put P 10 1 2 3 4 5 6 -1\nget P 10\n"
    result = cli(env, "--json", "run", "-", stdin=script)
    assert result.returncode == 0, result.stderr
    put, get = json_lines(result.stdout)
    assert put.keys() >= JSON_KEYS
    assert put["request"] == "PUT:RC8:10:P:8196,1,2,3,4,5,6,-1"
    assert put["response"] == "0"
    assert put["ok"] is True
    assert put["result"] == 0
    assert put["result_name"] == "S_OK"
    assert put["vt"] is None
    assert put["value"] is None
    assert "error" not in put

    assert get.keys() >= JSON_KEYS
    assert get["request"] == "GET:RC8:10:P:"
    assert get["response"] == "0,8196,1,2,3,4,5,6,-1"
    assert get["ok"] is True
    assert get["result"] == 0
    assert get["result_name"] == "S_OK"
    assert get["vt"] == 8196
    assert get["value"] == [1, 2, 3, 4, 5, 6, -1]
    assert isinstance(get["rtt_ms"], (int, float))
    assert get["rtt_ms"] >= 0
    assert "error" not in get
    assert (put["line"], get["line"]) == (1, 2)


def test_json_get_is_one_object(env: dict[str, str]) -> None:
    result = cli(env, "--json", "get", "P", "1")
    assert result.returncode == 0, result.stderr
    (data,) = json_lines(result.stdout)
    assert data.keys() >= JSON_KEYS
    assert data["request"] == "GET:RC8:1:P:"
    assert data["vt"] == 8196
    assert data["value"] == [350, 0, 450, 180, 0, 180, 5]
    assert data["response"] == "0,8196,350,0,450,180,0,180,5"


def test_send_prints_the_reply_as_it_came(env: dict[str, str]) -> None:
    result = cli(env, "send", "GET:RC8:10:I:")
    assert result.returncode == 0, result.stderr
    assert result.stdout.split()[0] == "0,3,0"


def test_send_short_io_put_is_a_controller_error(env: dict[str, str]) -> None:
    result = cli(env, "send", "PUT:RC8:10:11,0")
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    assert "E_INVALIDCOMMAND" in result.stderr


def test_json_controller_error_has_an_error_key(env: dict[str, str]) -> None:
    result = cli(env, "--json", "send", "PUT:RC8:10:11,0")
    assert result.returncode == 1
    (data,) = json_lines(result.stdout)
    assert data.keys() >= JSON_KEYS
    assert data["ok"] is False
    assert data["result"] == 0x80010005
    assert data["result_name"] == "E_INVALIDCOMMAND"
    assert data["response"] == "-2147418107"
    assert "E_INVALIDCOMMAND" in data["error"]


def test_version_and_help(env: dict[str, str]) -> None:
    result = cli(env, "--version")
    assert result.returncode == 0
    assert result.stdout.strip() == "rac-console 0.1.0"

    result = cli(env, "--help")
    assert result.returncode == 0
    assert result.stdout.startswith("usage: rac-console")
    for word in ("get", "put", "send", "run", "sim", "--json", "--read-only", "--timeout"):
        assert word in result.stdout
    assert result.stderr == ""


# ------------------------------------------------- typed PUTs on the wire


@pytest.mark.parametrize(
    ("args", "wire"),
    [
        (["put", "I", "10", "123"], b"PUT:RC8:10:I:3,123\r"),
        (["put", "I", "10", "-5"], b"PUT:RC8:10:I:3,-5\r"),
        (["put", "F", "10", "123.01"], b"PUT:RC8:10:F:4,123.01\r"),
        (["put", "D", "10", "123.01"], b"PUT:RC8:10:D:5,123.01\r"),
        (["put", "S", "10", "Sample,Test"], b"PUT:RC8:10:S:8,Sample,Test\r"),
        (["put", "V", "10", "1", "2", "3"], b"PUT:RC8:10:V:8196,1,2,3\r"),
        (
            ["put", "P", "10", "1", "2", "3", "4", "5", "6", "-1"],
            b"PUT:RC8:10:P:8196,1,2,3,4,5,6,-1\r",
        ),
        (
            ["put", "J", "10", *"12345678"],
            b"PUT:RC8:10:J:8196,1,2,3,4,5,6,7,8\r",
        ),
        (
            ["put", "T", "10", *"123456789", "-1"],
            b"PUT:RC8:10:T:8196,1,2,3,4,5,6,7,8,9,-1\r",
        ),
        (["put", "IO", "10", "on"], b"PUT:RC8:10:IO:11,-1\r"),
        (["put", "IO", "10", "off"], b"PUT:RC8:10:IO:11,0\r"),
        (["put", "IO", "10", "1"], b"PUT:RC8:10:IO:11,-1\r"),
        (["put", "IO", "10", "0"], b"PUT:RC8:10:IO:11,0\r"),
        (["put", "IO", "10", "true"], b"PUT:RC8:10:IO:11,-1\r"),
        (["put", "IO", "10", "false"], b"PUT:RC8:10:IO:11,0\r"),
        (["get", "I", "10"], b"GET:RC8:10:I:\r"),
        (["get", "P", "10"], b"GET:RC8:10:P:\r"),
        (["get", "IO", "10"], b"GET:RC8:10:IO:\r"),
    ],
    ids=lambda value: value.decode().strip() if isinstance(value, bytes) else " ".join(value),
)
def test_wire_bytes_of_typed_commands(
    env: dict[str, str], recording: Callable[..., RecordingServer], args: list[str], wire: bytes
) -> None:
    server = recording()
    result = cli(env, *server.args, "--no-verify", *args)  # the PUT alone: no read-back
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert len(server.connections()) == 1
    assert bytes(server.received) == wire


def test_get_shows_the_value_from_the_server(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording()
    result = cli(env, *server.args, "get", "I", "10")
    assert result.returncode == 0, result.stderr
    assert result.stdout.split()[:3] == ["I10", "=", "123"]
    assert bytes(server.received) == b"GET:RC8:10:I:\r"

    result = cli(env, *server.args, "--json", "get", "F", "10")
    assert result.returncode == 0, result.stderr
    (data,) = json_lines(result.stdout)
    assert data["response"] == "0,4,123.01"
    assert (data["vt"], data["value"]) == (4, 123.01)


@pytest.mark.parametrize("kind", ["V", "J", "T"])
def test_array_put_needs_its_exact_count(
    env: dict[str, str], recording: Callable[..., RecordingServer], kind: str
) -> None:
    count = {"V": 3, "J": 8, "T": 10}[kind]
    server = recording()
    for wrong in (count - 1, count + 1):
        result = cli(env, *server.args, "put", kind, "10", *["1"] * wrong)
        assert result.returncode == 2
        assert str(count) in one_error_line(result)
    assert server.connections() == []
    assert bytes(server.received) == b""


# --------------------------------------------- refused before sending (exit 2)


@pytest.mark.parametrize(
    "args",
    [
        ["get", "X", "1"],
        ["get", "I", "abc"],
        ["get", "I", "-1"],
        ["get", "I", "40000"],
        ["put", "I", "10", "abc"],
        ["put", "I", "10", "1.5"],
        ["put", "F", "10", "x"],
        ["put", "P", "10", "1", "2", "3"],
        ["put", "P", "10", "1", "2", "3", "4", "5", "6", "x"],
        ["put", "I", "10", "99999999999"],
        ["put", "F", "10", "1e39"],
        ["put", "D", "10", "1e309"],
        ["put", "IO", "10", "maybe"],
        ["put", "I", "10"],
        ["put", "S", "10", "a\rb"],
        ["put", "S", "10", "a\nb"],
        ["put", "S", "10", "x" * 300],
        ["send", "GET:RC8:10:I:\rGET:RC8:11:I:"],
        ["send", "x" * 300],
        ["send", "GET:RC8:10:S:é"],
        ["--read-only", "put", "I", "1", "5"],
        ["--read-only", "send", "PUT:RC8:1:I:3,1"],
        ["--read-only", "send", "  put:rc8:1:I:3,1"],
    ],
    ids=lambda args: " ".join(args)[:40].replace("\r", "<CR>").replace("\n", "<LF>"),
)
def test_bad_input_is_refused_with_nothing_on_the_wire(
    env: dict[str, str], recording: Callable[..., RecordingServer], args: list[str]
) -> None:
    server = recording()
    result = cli(env, *server.args, *args)
    assert result.returncode == 2, (result.stdout, result.stderr)
    one_error_line(result)
    assert result.stdout == ""
    assert server.connections() == []
    assert bytes(server.received) == b""


def test_read_only_still_reads(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording()
    result = cli(env, *server.args, "--read-only", "get", "I", "10")
    assert result.returncode == 0, result.stderr
    script = "PUT:RC8:1:I:3,1\nget I 10\n"  # run stops at a refused line unless told
    result = cli(env, *server.args, "--read-only", "run", "--keep-going", "-", stdin=script)
    assert result.returncode == 2
    assert "read-only" in result.stderr
    assert bytes(server.received) == b"GET:RC8:10:I:\r" * 2


def test_json_refusal_is_one_object(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording()
    result = cli(env, *server.args, "--json", "put", "I", "10", "abc")
    assert result.returncode == 2
    (data,) = json_lines(result.stdout)
    assert data.keys() >= JSON_KEYS
    assert data["ok"] is False
    assert data["response"] is None
    assert data["result"] is None
    assert "abc" in data["error"]
    assert server.connections() == []


# ------------------------------------------------------ transport (exit 3)


def test_connection_refused_is_exit_3(env: dict[str, str]) -> None:
    port = unused_port()
    result = cli(env, "-H", "127.0.0.1", "-p", str(port), "get", "I", "10")
    assert result.returncode == 3
    line = one_error_line(result)
    assert f"127.0.0.1:{port}" in line


def test_timeout_is_exit_3(env: dict[str, str], recording: Callable[..., RecordingServer]) -> None:
    server = recording(fixed_reply(None))
    result = cli(env, *server.args, "--timeout", "0.3", "get", "I", "10")
    assert result.returncode == 3
    assert "0.3" in one_error_line(result)  # its own timeout ended it, not the default
    assert bytes(server.received) == b"GET:RC8:10:I:\r"


def test_timed_out_put_says_the_outcome_is_unknown(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording(fixed_reply(None))
    args = ("--timeout", "0.3", "--json", "--no-verify")  # not stopped by a read before
    result = cli(env, *server.args, *args, "put", "I", "10", "1")
    assert result.returncode == 3
    (data,) = json_lines(result.stdout)
    assert data["ok"] is False
    assert "unknown" in data["error"]
    assert data["request"] == "PUT:RC8:10:I:3,1"


@pytest.mark.parametrize(
    ("reply", "shown"),
    [(b"\xff\xfe\r", "\\xff\\xfe"), (b"0,3,abc\r", "0,3,abc"), (b"0,8,text\r", "0,8,text")],
    ids=["not-ascii", "bad-integer", "wrong-type"],
)
def test_garbled_reply_is_exit_3_and_shown_escaped(
    env: dict[str, str], recording: Callable[..., RecordingServer], reply: bytes, shown: str
) -> None:
    server = recording(fixed_reply(reply))
    result = cli(env, *server.args, "get", "I", "10")
    assert result.returncode == 3
    assert shown in one_error_line(result)

    result = cli(env, *server.args, "--json", "get", "I", "10")
    assert result.returncode == 3
    (data,) = json_lines(result.stdout)
    assert data["ok"] is False
    assert data["response"] == shown
    assert data["error"]


def test_closed_without_reply_is_exit_3(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording(fixed_reply(b"0,3,1"), answers=1)  # cut short, then closed
    port = server.port
    result = cli(env, "-H", "127.0.0.1", "-p", str(port), "get", "I", "10")
    assert result.returncode == 3
    assert "0,3,1" in one_error_line(result)


# ----------------------------------------------- controller errors (exit 1)


@pytest.mark.parametrize("code", [b"0x80070057", b"-2147024809", b"2147942487"])
def test_controller_error_is_exit_1(
    env: dict[str, str], recording: Callable[..., RecordingServer], code: bytes
) -> None:
    server = recording(fixed_reply(code + b"\r"))
    result = cli(env, *server.args, "get", "P", "10")
    assert result.returncode == 1
    assert "E_INVALIDARG" in one_error_line(result)

    result = cli(env, *server.args, "--json", "put", "I", "10", "1")
    assert result.returncode == 1
    (data,) = json_lines(result.stdout)
    assert data.keys() >= JSON_KEYS
    assert data["ok"] is False
    assert data["result"] == E_INVALIDARG
    assert data["result_name"] == "E_INVALIDARG"
    assert data["response"] == code.decode()
    assert "E_INVALIDARG" in data["error"]


# ------------------------------------------------------------------- run

SCRIPT = """\
# a comment, then a blank line

get I 10
PUT:RC8:10:S:8,a b,c
   # an indented comment
put IO 10 on
GET:RC8:10:P:
send GET:RC8:10:T:
"""
SCRIPT_WIRE = b"".join(
    [
        b"GET:RC8:10:I:\r",
        b"PUT:RC8:10:S:8,a b,c\r",
        b"PUT:RC8:10:IO:11,-1\r",
        b"GET:RC8:10:P:\r",
        b"GET:RC8:10:T:\r",
    ]
)


def test_run_file_uses_one_session(
    env: dict[str, str], recording: Callable[..., RecordingServer], tmp_path: Path
) -> None:
    path = tmp_path / "script.rac"
    path.write_text(SCRIPT, encoding="utf-8")
    server = recording()
    result = cli(env, *server.args, "--no-verify", "run", str(path))
    assert result.returncode == 0, result.stderr
    assert bytes(server.received) == SCRIPT_WIRE
    assert len(server.connections()) == 1
    assert "I10 = 123" in result.stdout


def test_run_stdin_json_one_object_per_command_line(
    env: dict[str, str], recording: Callable[..., RecordingServer]
) -> None:
    server = recording()
    result = cli(env, *server.args, "--json", "--no-verify", "run", "-", stdin=SCRIPT)
    assert result.returncode == 0, result.stderr
    objects = json_lines(result.stdout)
    assert [o["line"] for o in objects] == [3, 4, 6, 7, 8]
    assert [o["request"] for o in objects] == [
        "GET:RC8:10:I:",
        "PUT:RC8:10:S:8,a b,c",
        "PUT:RC8:10:IO:11,-1",
        "GET:RC8:10:P:",
        "GET:RC8:10:T:",
    ]
    for data in objects:
        assert data.keys() >= JSON_KEYS
        assert data["ok"] is True
    assert objects[3]["value"] == [1, 2, 3, 4, 5, 6, -1]
    assert bytes(server.received) == SCRIPT_WIRE
    assert len(server.connections()) == 1


def _script_reply(line: bytes) -> bytes | None:
    if line == b"GET:RC8:98:I:":
        return None  # never answered: a timeout
    if line == b"GET:RC8:99:I:":
        return b"0x80070057\r"
    return sample_reply(line)


@pytest.mark.parametrize(
    ("lines", "status"),
    [
        (["get I 10", "get I 10"], 0),
        (["get I 99", "get I 10"], 1),
        (["get I 10", "get X 1", "get I 99"], 2),
        (["get I 99", "frobnicate", "get I 10"], 2),
        (["get I 98", "get I 99", "get X 1", "get I 10"], 3),
        (["get X 1", "get I 98"], 3),
    ],
    ids=["ok", "error", "refused", "unknown-command", "timeout", "timeout-last"],
)
def test_run_exit_status_is_the_worst(
    env: dict[str, str], recording: Callable[..., RecordingServer], lines: list[str], status: int
) -> None:
    server = recording(_script_reply)
    script = "\n".join(lines) + "\n"
    result = cli(
        env, *server.args, "--timeout", "0.3", "--json", "run", "--keep-going", "-", stdin=script
    )
    assert result.returncode == status, result.stderr
    assert "Traceback" not in result.stderr
    objects = json_lines(result.stdout)
    assert [o["line"] for o in objects] == list(range(1, len(lines) + 1))
    sent = [line for line in lines if line.startswith("get I")]
    assert server.lines == [f"GET:RC8:{line.split()[2]}:I:".encode() for line in sent]


def test_run_missing_file(env: dict[str, str], tmp_path: Path) -> None:
    result = cli(env, "run", str(tmp_path / "nope.rac"))
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert "nope.rac" in result.stderr


# ------------------------------------------------- a shared simulator server


@pytest.fixture
def sim_server(env: dict[str, str]) -> Iterator[int]:
    process = subprocess.Popen(
        [sys.executable, "-m", "rac_console", "sim", "--port", "0"],
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    lines: queue.Queue[str] = queue.Queue()

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            lines.put(line)

    threading.Thread(target=read, daemon=True).start()
    try:
        line = lines.get(timeout=10)
        prefix = "RC8 simulator listening on 127.0.0.1:"
        assert line.startswith(prefix), line
        assert line.rstrip().endswith("(Ctrl-C to stop)")
        yield int(line[len(prefix) :].split()[0])
    finally:
        process.terminate()
        try:
            process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=5)
        if process.stderr is not None:
            process.stderr.close()


def test_state_persists_on_a_shared_simulator(env: dict[str, str], sim_server: int) -> None:
    target = ["-H", "127.0.0.1", "-p", str(sim_server)]
    result = cli(env, *target, "put", "I", "5", "42")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""

    result = cli(env, *target, "get", "I", "5")
    assert result.returncode == 0, result.stderr
    assert result.stdout.split()[:3] == ["I5", "=", "42"]

    result = cli(env, *target, "--json", "get", "I", "5")
    (data,) = json_lines(result.stdout)
    assert (data["response"], data["vt"], data["value"]) == ("0,3,42", 3, 42)

    result = cli(env, *target, "send", "PUT:RC8:10:11,0")
    assert result.returncode == 1
    assert "E_INVALIDCOMMAND" in one_error_line(result)


def test_latency_reports_round_trip_statistics_as_json() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "--json", "latency", "--count", "200"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert set(summary) == {
        "count",
        "errors",
        "min_ms",
        "avg_ms",
        "p50_ms",
        "p95_ms",
        "max_ms",
        "requests_per_s",
    }
    assert summary["count"] == 200 and summary["errors"] == 0
    assert summary["min_ms"] <= summary["p50_ms"] <= summary["p95_ms"] <= summary["max_ms"]
    assert summary["requests_per_s"] > 0


def test_latency_against_nothing_is_exit_3_with_one_line() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "-H", "127.0.0.1", "-p", str(port), "latency"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 3
    assert result.stderr.strip().splitlines() == [
        f"rac-console: cannot connect to 127.0.0.1:{port}: Connection refused"
    ]


def test_cli_refuses_a_huge_index_without_a_traceback() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "get", "I", "9" * 5000],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr and "index" in result.stderr


def test_record_file_that_cannot_be_opened_is_a_clear_error(tmp_path: Path) -> None:
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "rac_console",
            "--record",
            str(tmp_path / "no" / "x.jsonl"),
            "get",
            "I",
            "1",
        ],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 2
    assert "cannot write the record file" in result.stderr and "Traceback" not in result.stderr
