"""The console on a cell of two simulators in a real terminal (tmux), read back from
the screen: rows of both targets, ``@NAME get`` answered by that target. Skipped
where tmux is missing (.ci/run installs it)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from tests.support.drivers import Terminal

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "cell_console.py"


@pytest.mark.slow
def test_a_cell_of_two_in_a_terminal(terminal: Terminal) -> None:
    command = f"{sys.executable} {SCRIPT} 2"
    terminal.tmux("new-session", "-d", "-s", "t", "-x", "120", "-y", "40", command)
    terminal.until("type help")  # the welcome: the engines have started
    terminal.tmux("send-keys", "-t", "t", "watch I 10 parts", "Enter")
    terminal.until("watching I10")
    terminal.tmux("send-keys", "-t", "t", "@robotB watch IO 64 go", "Enter")
    screen = terminal.until("Watch  2 rows")
    rows = [line for line in screen.splitlines() if "I10" in line or "IO64" in line]
    assert any("robotA" in line and "I10" in line for line in rows), screen
    assert any("robotB" in line and "IO64" in line for line in rows), screen
    terminal.tmux("send-keys", "-t", "t", "@robotB get I 1", "Enter")
    screen = terminal.until("I1 = ")
    assert "robotB › get I 1" in screen
    badges = screen.splitlines()[0]
    assert "robotA" in badges and "robotB" in badges and badges.count("connected") == 2
