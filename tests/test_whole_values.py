"""Every value shown whole: a put of P, J and T at 80x24, 100x30 and 120x40, each of its
numbers found in full on screen, in the results pane as drawn (nothing under its
scrollbar, nothing cut at a wrap) and, in the frame log, a line too long for the width
ends in "…" rather than in a number that reads as whole."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from textual.widgets import RichLog

from rac_console.tui.app import RacConsoleApp
from rac_console.tui.frame_log import FrameLog
from tests.support.drivers import make_app, type_line, until

pytestmark = pytest.mark.slow  # a console a size, seconds each

PUTS = {
    # As a newcomer typed them: "J3 3." was drawn, its 5 under the scrollbar; P lost its 6.
    "J as seen": ("put J 1 1.5 2.5 3.5 4.5 5.5 6.5 7.5 8.5", "J1"),
    "P as seen": ("put P 10 1 2 3 4 5 6 -1", "P10"),
    "J": ("put J 1 1.25 2.5 3.75 4.125 5.5 6.625 7.75 8.875", "J1"),
    "P": ("put P 10 10.5 20.25 30.125 40.5 50.75 60.875 -1", "P10"),
    "T": ("put T 1 1.5 2.5 3.5 4.5 5.5 6.5 7.5 8.5 9.5 10.5", "T1"),
}


def screen_rows(app: RacConsoleApp) -> list[str]:
    return [strip.text for strip in app.screen._compositor.render_strips()]


def whole(value: str, text: str) -> int:
    """How often ``value`` stands whole in ``text`` (no digit or point against it)."""
    return len(re.findall(rf"(?<![\d.]){re.escape(value)}(?![\d.])", text))


def results_as_drawn(app: RacConsoleApp) -> list[tuple[str, str]]:
    """The results pane's rows on screen, each beside the line the pane holds there."""
    pane = app.query_one("#results", RichLog)
    region = pane.content_region
    rows = screen_rows(app)
    top = int(pane.scroll_offset.y)
    drawn = []
    for i in range(region.height):
        held = pane.lines[top + i].text.rstrip() if top + i < len(pane.lines) else ""
        row = rows[region.y + i][region.x : region.x + region.width + 2]
        drawn.append((held, row))
    return drawn


@pytest.mark.parametrize("size", [(80, 24), (100, 30), (120, 40)], ids=lambda s: f"{s[0]}x{s[1]}")
@pytest.mark.parametrize("kind", list(PUTS))
async def test_a_put_of_many_numbers_shows_every_one_whole(
    tmp_path: Path, size: tuple[int, int], kind: str
) -> None:
    line, name = PUTS[kind]
    values = line.split()[3:]
    app = make_app(tmp_path)
    async with app.run_test(size=size) as pilot:
        await type_line(pilot, line)
        pane = app.query_one("#results", RichLog)
        await until(pilot, lambda: any("read back" in s.text for s in pane.lines), "the read-back")
        await pilot.pause()  # the screen drawn after the write (no time: until it is idle)
        held = "\n".join(strip.text for strip in pane.lines)
        for value in values:  # the new value and its read-back, each in one piece
            assert whole(value, held) >= 2, f"{name} {value} cut in the pane:\n{held}"
        for kept, row in results_as_drawn(app):
            assert kept in row, f"drawn {row!r}, the pane holds {kept!r}"
        log = app.query_one(FrameLog)
        width = log.scrollable_content_region.width
        region = log.content_region
        rows = screen_rows(app)[region.y : region.y + region.height]
        for row in rows:
            shown = row[region.x : region.x + width]
            if len(shown.rstrip()) == width:  # as wide as the pane: was it cut?
                full = next((ln for ln in log.lines if ln.startswith(shown[:24])), "")
                if len(full) > width:
                    assert shown.endswith("…"), f"a cut frame line reads as whole: {shown!r}"
