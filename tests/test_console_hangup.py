"""A console whose terminal goes away ends, instead of reading nothing for ever.

Textual's input thread takes the empty read of a hung-up terminal for piped input and
reads again: with no controlling terminal (so no SIGHUP), the console spun at two thirds
of a CPU after its pty closed. Both ways a terminal goes are tried here: the pty closed
under a console that has no controlling terminal, and a SIGHUP from the one it has.
"""

from __future__ import annotations

import os
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.tui.hangup import HANGUP_STATUS

fcntl = pytest.importorskip("fcntl")  # POSIX
termios = pytest.importorskip("termios")  # POSIX
from tests.support.drivers import read_until, spawn_console, stop  # noqa: E402

#: A terminal app in a subprocess: `pytest -m "not slow"` skips it.
pytestmark = pytest.mark.slow

DEADLINE = 20.0


def controlling_terminal() -> None:
    """In the child: a session of its own, with the pty as its controlling terminal."""
    os.setsid()
    fcntl.ioctl(0, termios.TIOCSCTTY, 0)


def start_console(
    tmp_path: Path, preexec: Callable[[], None] | None
) -> tuple[int, subprocess.Popen[bytes]]:
    """The console on the built-in simulator in a 120x40 pty, once it has connected."""
    master, process = spawn_console(tmp_path, preexec)
    try:
        seen = read_until(master, lambda seen: b"connected" in seen, DEADLINE)
        assert b"connected" in seen, seen[-2000:]  # not a terminal gone before it
    except AssertionError:
        stop(process)
        os.close(master)
        raise
    return master, process


def exit_status_once_gone(master: int, process: subprocess.Popen[bytes]) -> int | None:
    """Close the terminal; the console's exit status, or None if it still runs."""
    os.close(master)
    try:
        return process.wait(timeout=DEADLINE)
    except subprocess.TimeoutExpired:
        return None
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(10)


def test_the_console_ends_when_its_pty_closes_without_a_sighup(tmp_path: Path) -> None:
    master, process = start_console(tmp_path, None)  # no controlling terminal: no SIGHUP
    assert exit_status_once_gone(master, process) == HANGUP_STATUS


def test_the_console_ends_cleanly_on_sighup(tmp_path: Path) -> None:
    master, process = start_console(tmp_path, controlling_terminal)
    assert exit_status_once_gone(master, process) == HANGUP_STATUS  # not killed by it
