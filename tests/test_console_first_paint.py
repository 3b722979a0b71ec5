"""In a real terminal the console paints its target first and starts the engine after:
the first screen already names the simulator, and the welcome and the connection follow.

A headless app (every Pilot test) starts the engine at mount instead, so this path is
only seen in a pty.
"""

from __future__ import annotations

import os
import select
import subprocess
import sys
import time
from pathlib import Path

import pytest

pty = pytest.importorskip("pty")  # POSIX: a pty
#: A terminal app in a subprocess: `pytest -m "not slow"` skips it.
pytestmark = pytest.mark.slow

DEADLINE = 20.0


def test_the_first_screen_names_the_target_then_the_engine_starts(tmp_path: Path) -> None:
    env = os.environ | {
        "HOME": str(tmp_path),
        "XDG_STATE_HOME": str(tmp_path),
        "XDG_CONFIG_HOME": str(tmp_path),
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
    )
    os.close(slave)
    seen = b""
    first_screen: bytes | None = None
    try:
        started = time.monotonic()
        while b"built-in RC8 simulator" not in seen or b"connected" not in seen:
            assert time.monotonic() - started < DEADLINE, seen[-2000:]
            ready, _, _ = select.select([master], [], [], 0.2)
            if not ready:
                continue
            try:
                seen += os.read(master, 65536)
            except OSError:
                break
            if first_screen is None and b"SIMULATOR" in seen:
                first_screen = seen
    finally:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=10)
        os.close(master)
    assert first_screen is not None
    assert b"built-in RC8 simulator" in seen  # the welcome, once the engine started
    assert b"connected" in seen
