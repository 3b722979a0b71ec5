"""The console as it starts in a real terminal. Keys typed as soon as it has painted act: tmux (a
terminal: the engine starts after the first paint only there), keys sent the moment
the first screen shows, before the engine has started."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pytest

from tests.support.drivers import TERMINAL_DEADLINE as DEADLINE
from tests.support.drivers import Terminal

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


def test_the_demo_cell_opens_watching_its_handshake_and_says_its_targets_are_simulators(
    terminal: Terminal,
) -> None:
    command = f"{sys.executable} -m rac_console --cell demo"
    terminal.tmux("new-session", "-d", "-s", "t", "-x", "120", "-y", "40", command)
    screen = terminal.until("are simulators")
    assert "robotA and robotB are simulators playing a handshake, not controllers" in screen
    end = time.monotonic() + DEADLINE
    while "Watch  2 rows" not in (screen := terminal.screen()):
        assert time.monotonic() < end, f"the handshake not watched:\n{screen}"
        time.sleep(0.1)  # between looks at the screen, until the deadline
    table = screen.split("Frames")[0]
    assert "IO128" in table and "part placed" in table and "IO64" in table


def test_a_line_and_its_enter_typed_before_the_console_has_started_run(
    terminal: Terminal,
) -> None:
    """Keys typed while the console is still starting reach it through the terminal's
    cooked mode, where Enter arrives as a line feed (Ctrl+J): it runs the line as Enter
    does, not left on the command line."""
    terminal.start(ascii_mode=False)
    terminal.tmux("send-keys", "-t", "t", "get I 4", "Enter")  # at once: before raw mode
    screen = terminal.until("I4 = ")
    assert "› get I 4" in screen, screen
