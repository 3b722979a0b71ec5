"""Read-only is a whitelist, and controller text never reaches a terminal raw.

The real CLI as a subprocess against servers written here (127.0.0.1, port 0);
assertions are on the bytes the server received and the bytes the CLI printed.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.support.drivers import cli
from tests.support.servers import RecordingServer

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

#: Bytes that would act on a terminal: ESC, BEL, BS, and the C1 CSI byte.
TERMINAL_CONTROLS = ("\x1b", "\x07", "\x08", "\x9b")

#: A reply a hostile controller might send, all ASCII (a well-formed VT_BSTR): an OSC
#: title, an OSC 52 clipboard write, a CSI, BEL and backspace, and emoji codes.
HOSTILE = b"0,8,\x1b]0;pwned\x07 \x1b]52;c;ZWNobyBoaQ==\x07 \x1b[2J bell\x07 bs\x08 :V: :smile:\r"


def hostile_reply(line: bytes) -> bytes:
    if b":F:" in line:
        return b"0,4,1\x9b31m\r"  # the C1 CSI: not ASCII, so a garbled reply
    if line.startswith(b"PUT:"):
        return b"-2147024809,\x1b]0;title\x07\r"  # an error reply carrying an escape
    if b":I:" in line:
        return b"\x1b]0;garbled\x07\r"  # garbled: quoted in the error message
    return HOSTILE


def assert_no_terminal_controls(*texts: str) -> None:
    for text in texts:
        for control in TERMINAL_CONTROLS:
            assert control not in text, f"{control!r} reached the terminal: {text!r}"


@pytest.mark.parametrize(
    "request_text",
    [
        "\x01PUT:RC8:1:I:3,5",
        " PUT:RC8:1:I:3,5",
        "SIM:SET:delay_ms=5",
        "GET:RC8:1:I:3,5",  # a GET carrying a parameter is not a well-formed GET
        "GET:RC8:1:I:\x1b",
        "GET:RC8:1:X:",
        "hello",
    ],
)
def test_read_only_sends_nothing_but_well_formed_gets(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
    request_text: str,
) -> None:
    server = recording()
    result = cli(env, *server.args, "--read-only", "send", request_text)
    assert result.returncode == 2, result.stderr
    assert "read-only" in result.stderr
    assert server.connections() == []  # not even a connection
    assert server.received == b""


def test_read_only_lets_well_formed_gets_through(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording()
    script = "get I 1\nGET:RC8:2:P:\nsend GET:RC8:3:IO:\nput I 1 5\nsend SIM:GET:\n"
    result = cli(env, *server.args, "--read-only", "run", "--keep-going", "-", stdin=script)
    assert result.returncode == 2
    assert server.wait_received(3 * 12) == b"GET:RC8:1:I:\rGET:RC8:2:P:\rGET:RC8:3:IO:\r"
    assert result.stderr.count("read-only") == 2


@pytest.mark.parametrize(
    "args",
    [
        ("send", "GET:RC8:1:S:"),
        ("get", "S", "1"),
        ("--json", "send", "GET:RC8:1:S:"),
        ("--json", "get", "S", "1"),
        ("put", "S", "1", "x"),
        ("--json", "put", "S", "1", "x"),
        ("get", "I", "1"),
        ("--json", "get", "I", "1"),
        ("send", "GET:RC8:1:I:"),
        ("get", "F", "1"),
        ("--json", "send", "GET:RC8:1:F:"),
    ],
)
def test_controller_text_is_printed_escaped(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
    args: tuple[str, ...],
) -> None:
    server = recording(hostile_reply)
    result = cli(env, *server.args, *args)
    assert_no_terminal_controls(result.stdout, result.stderr)
    assert "Traceback" not in result.stderr
    shown = result.stdout + result.stderr
    # Shown escaped, not dropped (JSON escapes in its own way).
    assert any(mark in shown for mark in ("\\x1b", "\\u001b", "\\x9b"))
    assert "✌" not in shown and "😄" not in shown  # no emoji codes from the wire


def test_bel_and_backspace_are_shown_escaped_not_dropped(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording(lambda line: b"0,8,bell\x07 bs\x08\r")
    result = cli(env, *server.args, "get", "S", "1")
    assert result.returncode == 0
    assert "bell\\x07 bs\\x08" in result.stdout


def test_run_text_mode_escapes_replies_and_script_text(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording(hostile_reply)
    script = "get S 1\nsend GET:RC8:2:S:\n\x1b]0;from-file\x07frob\nget I 3\nput S 1 a\n"
    result = cli(env, *server.args, "run", "-", stdin=script)
    assert_no_terminal_controls(result.stdout, result.stderr)
    assert "\\x1b]0;pwned" in result.stdout
    assert "\\x1b]0;from-file" in result.stderr
    assert ":V:" in result.stdout


def test_json_error_line_keeps_colons_as_typed(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording(lambda line: b"-2147024809\r")
    result = cli(env, *server.args, "--json", "send", "GET:RC8:11:V:")
    assert result.returncode == 1
    assert "GET:RC8:11:V:" in result.stderr
    assert "✌" not in result.stderr


def test_a_controller_that_closes_at_once_is_not_a_timeout(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
) -> None:
    closer = recording(answers=0)  # closes every connection as soon as it accepts it
    port = closer.port
    for _ in range(5):  # the race has two sides: try it a few times
        result = cli(
            env,
            "-H",
            "127.0.0.1",
            "-p",
            str(port),
            "--timeout",
            "60",
            "run",
            "-",
            stdin="put I 1 5\n",
            timeout=30,
        )
        assert result.returncode == 3
        assert "closed the connection" in result.stderr
        assert "may have been applied" not in result.stderr


def test_a_port_without_a_host_is_refused(env: dict[str, str]) -> None:
    result = cli(env, "-p", "40653", "get", "I", "50")
    assert result.returncode == 2
    assert "-p 40653 needs -H HOST" in result.stderr
    assert result.stdout == ""


def test_the_console_without_a_terminal_says_so_and_exits(env: dict[str, str]) -> None:
    result = cli(env, "--json", timeout=30)  # stdin and stdout are pipes here
    assert result.returncode == 2
    assert "the console needs a terminal" in result.stderr
    assert "\x1b" not in result.stdout


def test_a_huge_garbage_reply_is_quoted_short(
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording(lambda line: b"Z" * 60_000 + b"\r")
    result = cli(env, *server.args, "get", "I", "1")
    assert result.returncode == 3
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and len(lines[0]) < 1000, len(result.stderr)
    assert "(60000 bytes)" in lines[0]
