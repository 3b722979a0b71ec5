"""In a real terminal the console paints its target first and starts the engine after:
the first screen already names the simulator, and the welcome and the connection follow.

A headless app (every Pilot test) starts the engine at mount instead, so this path is
only seen in a pty.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

pytest.importorskip("pty")  # POSIX: a pty
from tests.support.drivers import read_until, spawn_console, stop

#: A terminal app in a subprocess: `pytest -m "not slow"` skips it.
pytestmark = pytest.mark.slow

DEADLINE = 20.0


def test_the_first_screen_names_the_target_then_the_engine_starts(tmp_path: Path) -> None:
    master, process = spawn_console(tmp_path)
    first: list[bytes] = []  # what was on screen when it first named the simulator

    def note_first_screen(seen: bytes) -> None:
        if not first and b"SIMULATOR" in seen:
            first.append(seen)

    try:
        seen = read_until(
            master,
            lambda seen: b"built-in RC8 simulator" in seen and b"connected" in seen,
            DEADLINE,
            note_first_screen,
        )
    finally:
        stop(process)
        os.close(master)
    first_screen = first[0] if first else None
    assert first_screen is not None
    assert b"built-in RC8 simulator" in seen  # the welcome, once the engine started
    assert b"connected" in seen
