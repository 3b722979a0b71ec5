"""The command line and its completions at any terminal size down to 40x12 (issue 41):
the command line's row always on screen and focused, typing and Enter answered, the
completion list within the room there is (every candidate reachable by Tab again),
the hint line on screen too, and the table's rows left where they were."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from textual.pilot import Pilot

from rac_console.engine.commands.builtin import BUILTIN
from rac_console.present.completion import complete
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import make_app, results_text, type_line, until

#: Terminal apps: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

SIZES = [(40, 12), (50, 14), (80, 24), (120, 40)]


def screen_lines(app: RacConsoleApp) -> list[str]:
    """The screen as drawn, a line a row."""
    return [strip.text for strip in app.screen._compositor.render_strips()]


def command_row(app: RacConsoleApp) -> str:
    """The command line's row as drawn (failing when that row is off the screen)."""
    line = app.main_screen.panes.command_line
    y = line.region.y
    assert line.region.height == 1 and 0 <= y < app.size.height - 1, (
        f"the command line at row {y} of {app.size.height}: off the screen"
    )
    return screen_lines(app)[y]


def listed(app: RacConsoleApp) -> list[str]:
    """The first word of each line of the completion list as drawn on the screen."""
    panel = app.main_screen.panes.completions
    region = panel.region
    lines = [line[region.x : region.right] for line in screen_lines(app)[region.y : region.bottom]]
    assert all(line.strip() for line in lines), f"a blank line in the list: {lines}"
    return [line.split()[0] for line in lines]


async def every_candidate(pilot: Pilot[Any], app: RacConsoleApp, typed: str) -> set[str]:
    """Tab after ``typed``, then Tab again until the list shows its first page again:
    every candidate seen, each page checked to fit between the status line and the
    command line while the command line keeps its row, its text and the focus."""
    panes = app.main_screen.panes
    await type_line(pilot, typed, enter=False, keys=True)
    seen: set[str] = set()
    pages: list[list[str]] = []
    for _ in range(12):
        await pilot.press("tab")
        await until(pilot, lambda: panes.completions.has_class("-visible"), "the list")
        await pilot.pause()
        page = listed(app)
        if pages and page == pages[0]:
            break
        pages.append(page)
        seen.update(word for word in page if word != "…")
        region = panes.completions.region
        assert region.height >= 2, "no room for the list"
        assert region.y >= panes.status_bar.region.bottom, "the list over the status line"
        assert region.bottom <= panes.command_line.region.y, "the list over the command line"
        assert typed in command_row(app)
        assert app.focused is panes.command_line
    await pilot.press("ctrl+u")
    return seen


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
async def test_the_command_line_and_its_list_at_every_size(
    tmp_path: Path, size: tuple[int, int]
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=size) as pilot:
        panes = app.main_screen.panes
        await type_line(pilot, "watch J 0 T 0 IO 0-3")
        await until(pilot, lambda: panes.table.row_count == 6, "the six rows")
        assert app.focused is panes.command_line
        assert panes.command_line.placeholder[:12] in command_row(app)  # drawn, empty

        # Typing shows on its row, Enter runs it and the answer is on screen.
        await type_line(pilot, "get I 1", enter=False, keys=True)
        assert "get I 1" in command_row(app)
        await pilot.press("enter")
        await until(pilot, lambda: "I1 = " in results_text(app), "the get's answer")
        await until(pilot, lambda: any("I1 = " in line for line in screen_lines(app)), "shown")

        # The table's rows stay where they were while the list is open.
        table_before = panes.table.region
        types = await every_candidate(pilot, app, "get ")
        assert types == {c.text for c in complete("get ")}
        assert panes.table.region == table_before
        commands = await every_candidate(pilot, app, "help ")
        assert commands == set(BUILTIN.names())

        # The hint line (the history holds the grey text): on screen, above the line.
        await type_line(pilot, "get ", enter=False, keys=True)
        await until(pilot, lambda: panes.hint.has_class("-visible"), "the hint line")
        await pilot.pause()
        hint = panes.hint.region
        assert hint.height == 1 and hint.bottom <= panes.command_line.region.y
        assert "needs: TYPE INDEX" in screen_lines(app)[hint.y]
        await pilot.press("tab")
        await until(pilot, lambda: panes.completions.has_class("-visible"), "the list, hint on")
        await pilot.pause()
        assert panes.completions.region.bottom <= hint.y
        assert "get " in command_row(app) and app.focused is panes.command_line
