"""The console in a real pseudo-terminal (POSIX), for the tests of what only a terminal
shows: the first paint, a hang-up."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

pty = pytest.importorskip("pty")  # POSIX: a pty
select = pytest.importorskip("select")


def spawn_console(
    home: Path, preexec: Callable[[], None] | None = None
) -> tuple[int, subprocess.Popen[bytes]]:
    """``rac-console`` on the built-in simulator in a 120x40 pty, its files under
    ``home``: the pty's master side and the process."""
    env = os.environ | {
        "HOME": str(home),
        "XDG_STATE_HOME": str(home),
        "XDG_CONFIG_HOME": str(home),
        "TERM": "xterm-256color",
        "COLUMNS": "120",
        "LINES": "40",
    }
    master, slave = pty.openpty()
    process = subprocess.Popen(
        [sys.executable, "-m", "rac_console"],
        stdin=slave,
        stdout=slave,
        stderr=slave,
        env=env,
        close_fds=True,
        preexec_fn=preexec,
    )
    os.close(slave)
    return master, process


def read_until(
    master: int,
    done: Callable[[bytes], bool],
    deadline: float,
    seen_chunk: Callable[[bytes], None] = lambda seen: None,
) -> bytes:
    """What the console wrote until ``done(everything so far)`` (AssertionError with
    its last output after ``deadline`` seconds); ``seen_chunk`` sees it after each read.
    A terminal that hangs up ends the reading."""
    seen = b""
    started = time.monotonic()
    while not done(seen):
        assert time.monotonic() - started < deadline, seen[-2000:]
        ready, _, _ = select.select([master], [], [], 0.2)
        if not ready:
            continue
        try:
            seen += os.read(master, 65536)
        except OSError:
            break
        seen_chunk(seen)
    return seen


def stop(process: subprocess.Popen[bytes]) -> None:
    """End the console, killing it if it does not end."""
    if process.poll() is None:
        process.terminate()
    try:
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(timeout=10)
