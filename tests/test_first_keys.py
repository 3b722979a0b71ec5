"""Keys typed as soon as the console has painted act: the real console in tmux (a
terminal: the engine starts after the first paint only there), keys sent the moment
the first screen shows, before the engine has started."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from test_ascii_screen import DEADLINE, Terminal, terminal

terminal = terminal  # the fixture: a tmux server of the test's own

pytestmark = pytest.mark.slow


def test_up_and_enter_at_the_first_paint_run_and_lines_typed_ahead_follow(
    terminal: Terminal, tmp_path: Path
) -> None:
    history = tmp_path / "state" / "rac-console" / "history"
    history.parent.mkdir(parents=True)
    history.write_text("get I 2\n", encoding="utf-8")
    terminal.start(ascii_mode=False)
    end = time.monotonic() + DEADLINE
    while "SIMULATOR" not in terminal.screen():  # the first paint, before the engine runs
        assert time.monotonic() < end, "no first paint"  # each look is a tmux call
    terminal.tmux("send-keys", "-t", "t", "Up", "Enter")
    terminal.tmux("send-keys", "-t", "t", "get I 3", "Enter")
    screen = terminal.until("I3 = ")
    assert "I2 = " in screen, screen
    assert screen.index("I2 = ") < screen.index("I3 = ")
