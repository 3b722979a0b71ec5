"""The REPL runs typed lines exactly as typed, and prints controller text escaped.

prompt-toolkit's pipe input against the simulator or a hostile server written here.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.drivers import Driver
from tests.support.servers import RecordingServer

TERMINAL_CONTROLS = ("\x1b", "\x07", "\x08", "\x9b")


def sent(driver: Driver) -> list[bytes]:
    return driver.tap.sent


async def test_a_burst_of_lines_runs_each_once_in_order(tmp_path: Path) -> None:
    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type("put I 10 1\r5\rget I 1\rget I 2\rget I 3\r")
        await d.until(lambda out: "I3 = " in out, "the last line")

    out = await driver.run(steps)
    assert sent(driver) == [
        b"GET:RC8:10:I:\r",  # the value before
        b"PUT:RC8:10:I:3,1\r",
        b"GET:RC8:10:I:\r",  # read back
        b"GET:RC8:1:I:\r",
        b"GET:RC8:2:I:\r",
        b"GET:RC8:3:I:\r",
    ]
    assert "unknown command '5'" in out


def hostile_reply(line: bytes) -> bytes:
    """A string full of terminal controls and emoji codes; garbage for an I."""
    if b":I:" in line:
        return b"\x1b]0;garbled\x07\r"
    if b":F:" in line:
        return b"0,4,1\x9b31m\r"  # the C1 CSI byte
    return b"0,8,\x1b]0;pwned\x07 \x1b[2J bell\x07 bs\x08 :V: :smile:\r"


async def test_a_pasted_block_runs_line_by_line(tmp_path: Path) -> None:
    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type("\x1b[200~get I 1\nget I 2\nput I 10 7\x1b[201~\r")  # a bracketed paste
        await d.until(lambda out: "→ 7  S_OK  read back 7 ✓" in out, "the pasted lines")

    await driver.run(steps)
    assert sent(driver) == [
        b"GET:RC8:1:I:\r",
        b"GET:RC8:2:I:\r",
        b"GET:RC8:10:I:\r",
        b"PUT:RC8:10:I:3,7\r",
        b"GET:RC8:10:I:\r",
    ]


@pytest.fixture
def hostile_port() -> Iterator[int]:
    server = RecordingServer(hostile_reply)
    yield server.port
    server.close()


async def test_controller_text_is_printed_escaped(tmp_path: Path, hostile_port: int) -> None:
    driver = Driver(tmp_path, "127.0.0.1", port=hostile_port)

    async def steps(d: Driver) -> None:
        d.type("get S 1\r")
        await d.until(lambda out: "S1 = " in out, "the get")
        d.type("send GET:RC8:2:S:\r")
        await d.until(lambda out: out.count("pwned") >= 2, "the raw reply")
        d.type("get I 3\r")
        await d.until(lambda out: "bad reply" in out, "the garbled reply")
        d.type("get F 5\r")
        await d.until(lambda out: "\\x9b31m" in out, "the C1 reply, escaped")
        d.type("frames on\r")
        d.type("send GET:RC8:4:S:\r")
        await d.until(lambda out: out.count("pwned") >= 5, "the frames")

    out = await driver.run(steps)
    for control in TERMINAL_CONTROLS:
        assert control not in out
    assert "\\x1b]0;pwned\\x07" in out
    assert "bell\\x07 bs\\x08" in out
    assert ":V: :smile:" in out


async def test_argument_hint_stays_legible_beside_a_history_suggestion(tmp_path: Path) -> None:
    driver = Driver(tmp_path)
    driver.history.append("put P 10 1 2 3 4 5 6 -1")

    def toolbar_text() -> str:
        return "".join(text for _, text, *_ in driver.repl.toolbar())

    async def steps(d: Driver) -> None:
        d.type("put P 10 ")
        deadline = asyncio.get_running_loop().time() + 5
        while d.repl.prompt.default_buffer.suggestion is None:
            assert asyncio.get_running_loop().time() < deadline, "no history suggestion"
            await asyncio.sleep(0.02)
        assert "needs: X Y Z Rx Ry Rz Fig" in toolbar_text()
        d.type("\x15")  # Ctrl-U: an empty line has no hint
        while d.repl.prompt.default_buffer.text:
            assert asyncio.get_running_loop().time() < deadline, "the line was not cleared"
            await asyncio.sleep(0.02)
        assert "needs:" not in toolbar_text()

    await driver.run(steps)


@pytest.mark.slow
def test_ctrl_c_while_a_command_waits_cancels_it_and_keeps_the_repl() -> None:
    """At the cell, Ctrl-C gives up on a slow request; it must not end the session."""
    pty = pytest.importorskip("pty")  # a real terminal, so Ctrl-C is a signal
    import os
    import select
    import signal
    import sys
    import time

    silent = RecordingServer(lambda line: None)
    pid, fd = pty.fork()
    if pid == 0:  # the child: the REPL on a terminal, talking to a silent controller
        # Ctrl-C back to its default: run with SIGINT ignored (a background job, nohup),
        # the REPL would inherit that and never see the Ctrl-C below.
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.execvp(
            sys.executable,
            [
                sys.executable,
                "-m",
                "rac_console",
                "repl",
                "-H",
                "127.0.0.1",
                "-p",
                str(silent.port),
                "--timeout",
                "30",
            ],
        )
    output = b""

    def read_until(text: bytes, timeout: float = 15) -> None:
        nonlocal output
        deadline = time.monotonic() + timeout
        while text not in output:
            assert time.monotonic() < deadline, f"no {text!r} in {output[-400:]!r}"
            if select.select([fd], [], [], 0.1)[0]:
                output += os.read(fd, 65536)

    try:
        read_until(b"127.0.0.1:")  # the prompt names the controller
        os.write(fd, b"get I 1\r")
        assert silent.wait_received(len(b"GET:RC8:1:I:\r"), timeout=15)  # the GET went out
        os.write(fd, b"\x03")  # Ctrl-C while the GET waits (a 30 s timeout)
        read_until(b"cancelled")
        os.write(fd, b"help\r")
        read_until(b"leave (Ctrl+Q")  # the REPL is still there and answers
        assert os.waitpid(pid, os.WNOHANG) == (0, 0)
        os.write(fd, b"quit\r")
    finally:
        silent.close()
        with contextlib.suppress(OSError):
            os.kill(pid, 9)
        with contextlib.suppress(ChildProcessError):
            os.waitpid(pid, 0)
        os.close(fd)


@pytest.mark.parametrize("sequence", ["\x1b[M", "\x1b[<0;1M", "\x1b[M!"])
async def test_a_stray_mouse_sequence_is_ignored_not_a_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], sequence: str
) -> None:
    """A terminal (or a paste) can send a cut-short mouse report: prompt-toolkit's own
    handler failed on it with a traceback and the REPL stopped reading."""
    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type(sequence + "abc\r")  # an X10 report takes the 3 bytes after ESC [ M
        d.type("get I 1\r")
        await d.until(lambda out: "I1 = 1" in out, "the get after the sequence")

    await driver.run(steps)
    captured = capsys.readouterr()
    assert "Unhandled exception" not in captured.err + captured.out
    assert "Traceback" not in captured.err + captured.out
