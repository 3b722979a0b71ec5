"""The console in ASCII (issue 21, item 8): for Windows' old console host, whose fonts
lack ``↵ ● →`` and box drawing. The real console in a real terminal (tmux), read back
from the screen. Skipped where tmux is missing (.ci/run installs it)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.present.glyphs import SCREEN_TABLE, ascii_wanted

DEADLINE = 30.0


def test_ascii_is_asked_for_or_chosen_for_conhost() -> None:
    assert ascii_wanted({"RAC_CONSOLE_ASCII": "1"}, "linux")
    assert not ascii_wanted({}, "linux")
    assert ascii_wanted({}, "win32")  # conhost: no WT_SESSION
    assert not ascii_wanted({"WT_SESSION": "x"}, "win32")  # Windows Terminal
    assert not ascii_wanted({"RAC_CONSOLE_ASCII": "0"}, "win32")


def test_every_glyph_keeps_its_cell() -> None:
    for code, form in SCREEN_TABLE.items():
        assert len(form) == 1 and form.isascii(), (chr(code), form)


@pytest.fixture
def terminal(tmp_path: Path) -> Iterator[Terminal]:
    if shutil.which("tmux") is None:
        pytest.skip("needs tmux")
    made = Terminal(tmp_path)
    yield made
    made.close()


class Terminal:
    """A tmux server of its own, its environment private to the test."""

    def __init__(self, home: Path) -> None:
        self.socket = f"rac-ascii-{os.getpid()}-{id(self)}"
        self.env = {
            key: value for key, value in os.environ.items() if key not in ("COLUMNS", "LINES")
        }
        self.env.update(
            HOME=str(home),
            XDG_CONFIG_HOME=str(home / "config"),
            XDG_STATE_HOME=str(home / "state"),
            TERM="xterm-256color",
            LANG="C.UTF-8",
        )

    def tmux(self, *words: str) -> str:
        result = subprocess.run(
            ["tmux", "-L", self.socket, *words],
            env=self.env,
            capture_output=True,
            text=True,
            timeout=20,
        )
        return result.stdout

    def start(self, ascii_mode: bool) -> None:
        flag = "RAC_CONSOLE_ASCII=1" if ascii_mode else "RAC_CONSOLE_ASCII=0"
        command = f"env {flag} {sys.executable} -m rac_console"
        self.tmux("new-session", "-d", "-s", "t", "-x", "100", "-y", "30", command)

    def screen(self) -> str:
        return self.tmux("capture-pane", "-p", "-t", "t")

    def until(self, text: str) -> str:
        end = time.monotonic() + DEADLINE
        while True:
            screen = self.screen()
            if text in screen:
                return screen
            assert time.monotonic() < end, f"{text!r} not on the screen:\n{screen}"
            time.sleep(0.1)

    def close(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True, timeout=20)


@pytest.mark.slow
@pytest.mark.parametrize("ascii_mode", [True, False])
def test_the_console_draws_in_ascii_when_asked(terminal: Terminal, ascii_mode: bool) -> None:
    terminal.start(ascii_mode)
    terminal.until("SIMULATOR")
    terminal.tmux("send-keys", "-t", "t", "watch IO 0-7", "Enter")
    terminal.until("IO7")
    terminal.tmux("send-keys", "-t", "t", "get I 1", "Enter")
    screen = terminal.until("I1 = ")
    strange = sorted({ch for ch in screen if not ch.isascii()})
    if ascii_mode:
        assert strange == [], strange
    else:
        assert strange, "the glyphs and borders of the usual screen"
