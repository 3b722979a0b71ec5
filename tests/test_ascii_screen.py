"""The console in ASCII (issue 21, item 8): for Windows' old console host, whose fonts
lack ``↵ ● →`` and box drawing. The real console in a real terminal (tmux), read back
from the screen. Skipped where tmux is missing (.ci/run installs it)."""

from __future__ import annotations

import pytest

from rac_console.present.glyphs import SCREEN_TABLE, ascii_wanted
from tests.support.drivers import Terminal


def test_ascii_is_asked_for_or_chosen_for_conhost() -> None:
    assert ascii_wanted({"RAC_CONSOLE_ASCII": "1"}, "linux")
    assert not ascii_wanted({}, "linux")
    assert ascii_wanted({}, "win32")  # conhost: no WT_SESSION
    assert not ascii_wanted({"WT_SESSION": "x"}, "win32")  # Windows Terminal
    assert not ascii_wanted({"RAC_CONSOLE_ASCII": "0"}, "win32")


def test_every_glyph_keeps_its_cell() -> None:
    for code, form in SCREEN_TABLE.items():
        assert len(form) == 1 and form.isascii(), (chr(code), form)


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
