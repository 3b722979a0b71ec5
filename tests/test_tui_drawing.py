"""What the console draws after a change of size or of traffic (issue 20.12): the I/O
grid beside the table only where both fit, the hex view laid out again for the new
width, and the frame log's border counting the frames it shows."""

from __future__ import annotations

import gc
import re
from pathlib import Path

import pytest
from textual.pilot import Pilot

from rac_console.protocol import parse_request, parse_response
from rac_console.session import Frame
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.frame_lines import HEX_SEPARATOR
from rac_console.tui.frame_log import KEPT, KEPT_OTHERS, MAX_LINES, FrameLog
from tests.support.drivers import make_app, results_text, rows_read, type_line, until

REPLY = parse_response("0,3,1")
I1 = parse_request(b"GET:RC8:1:I:\r")


def add_exchanges(log: FrameLog, count: int, *, poll: bool, start: float = 1_700_000_000) -> None:
    """``count`` GETs and their replies, a millisecond apart."""
    for n in range(count):
        t = start + n / 1000
        log.add(Frame(t, "tx", b"GET:RC8:1:I:\r", poll=poll, request=I1))
        log.add(Frame(t + 0.0001, "rx", b"0,3,1\r", 0.0001, response=REPLY, poll=poll, request=I1))


def shown_of_kept(log: FrameLog) -> tuple[int, int]:
    match = re.search(r"(\d+) of (\d+) frames", log.title_text)
    assert match is not None, log.title_text
    return int(match.group(1)), int(match.group(2))


# ------------------------------------------------------------- the count


@pytest.mark.slow  # over half a second
def test_with_polls_hidden_the_border_counts_the_typed_frames_a_fast_poll_outlives() -> None:
    log = FrameLog()
    add_exchanges(log, KEPT, poll=True)
    log.flush()
    log.show_polls = False
    add_exchanges(log, 3, poll=False, start=1_700_000_100)  # typed: shown
    log.flush()
    assert shown_of_kept(log)[0] == 6
    add_exchanges(log, KEPT, poll=True, start=1_700_000_200)  # a fast poll goes on
    log.flush()
    shown, kept = shown_of_kept(log)
    assert shown == 6, log.title_text  # the typed frames are still there, and counted
    assert kept >= KEPT
    log.hex_view = True  # drawn again from what is kept: the typed frames stay
    assert shown_of_kept(log)[0] == 6


def test_a_filter_counts_what_it_shows_and_forgets_the_oldest() -> None:
    log = FrameLog()
    log.set_filter("IO128")
    add_exchanges(log, 10, poll=False)
    log.flush()
    assert shown_of_kept(log) == (0, 20)
    io128 = parse_request(b"GET:RC8:128:IO:\r")
    log.add(Frame(1_700_000_001, "tx", b"GET:RC8:128:IO:\r", request=io128))
    reply = parse_response("0,11,-1")
    log.add(Frame(1_700_000_001.1, "rx", b"0,11,-1\r", 0.0001, response=reply, request=io128))
    log.flush()
    assert shown_of_kept(log) == (2, 22)
    add_exchanges(log, KEPT_OTHERS, poll=False, start=1_700_000_100)  # pushes IO128 out
    log.flush()
    assert shown_of_kept(log) == (0, KEPT_OTHERS)


# ------------------------------------------------------------- the hex view


async def hex_lines_fit(pilot: Pilot, app: RacConsoleApp) -> list[str]:
    """The log's lines once laid out for its width (waited for, with a deadline); every
    hex line checked against the width."""
    log = app.main_screen.panes.frame_log

    await until(pilot, lambda: log.hex_laid_out, "the hex lines laid out for the log's width")
    width = log.scrollable_content_region.width
    for line in log.lines:
        if HEX_SEPARATOR in line:
            assert len(line) <= width, (width, line)
    return list(log.lines)


@pytest.mark.slow
async def test_after_a_resize_the_hex_view_is_laid_out_for_the_new_width(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(150, 40)) as pilot:
        for line in ("get I 1", "get P 1", "send hello there, a long raw line"):
            await type_line(pilot, line)
        await until(pilot, lambda: app.main_screen.panes.frame_log.frames_kept == 6, "six frames")
        await pilot.press("f7")
        for size in ((80, 30), (120, 30), (95, 24), (160, 50)):
            await pilot.resize_terminal(*size)
            resized = await hex_lines_fit(pilot, app)
            await pilot.press("f7", "f7")  # off and on: drawn afresh at this width
            fresh = await hex_lines_fit(pilot, app)
            assert resized == fresh, size


@pytest.mark.slow
async def test_a_request_and_its_reply_put_their_hex_the_same_way(tmp_path: Path) -> None:
    """At a width where the requests' bytes do not fit beside the replies' longer
    text, no line keeps its bytes beside it while the others have theirs under."""
    app = make_app(tmp_path)
    async with app.run_test(size=(150, 30)) as pilot:
        for _ in range(3):
            await type_line(pilot, "get I 1")
        await until(pilot, lambda: app.main_screen.panes.frame_log.frames_kept == 6, "six frames")
        await pilot.press("f7")
        await pilot.resize_terminal(85, 30)
        lines = await hex_lines_fit(pilot, app)
        assert app.main_screen.panes.frame_log.hex_placement in ("beside", "under"), lines
        await pilot.resize_terminal(150, 30)
        await hex_lines_fit(pilot, app)
        assert app.main_screen.panes.frame_log.hex_placement == "beside"


# ------------------------------------------------------------- the I/O grid


async def watch_rows(pilot: Pilot, lines: tuple[str, ...], rows: int) -> None:
    app = pilot.app
    assert isinstance(app, RacConsoleApp)
    for line in lines:
        await type_line(pilot, line)
    await rows_read(pilot, rows)


def table_cut(app: RacConsoleApp) -> bool:
    """True when the table's columns are wider than the room it has."""
    table = app.main_screen.panes.table
    return table.virtual_size.width > table.scrollable_content_region.width


@pytest.mark.slow
async def test_at_160_columns_the_grid_leaves_a_position_row_its_width(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(160, 50)) as pilot:
        await watch_rows(pilot, ("watch P 1 pick", "watch IO 128-143"), 17)
        await pilot.press("f5")
        await until(pilot, lambda: app.main_screen.panes.io_panel.grid is not None, "the grid")
        await until(pilot, lambda: not table_cut(app), "the table's columns laid out to fit")
        assert not table_cut(app), (
            app.main_screen.panes.table.virtual_size,
            app.main_screen.panes.table.size,
        )
        grid = app.main_screen.panes.io_panel.grid
        assert grid is not None and grid.layout.per_line == 16
        assert grid.layout.width <= app.main_screen.panes.io_panel.scrollable_content_region.width


@pytest.mark.slow
async def test_a_narrow_table_keeps_the_grid_beside_it_sized_to_the_grid(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(160, 50)) as pilot:
        await watch_rows(pilot, ("watch I 1", "watch IO 128-143"), 17)
        await pilot.press("f5")
        await until(pilot, lambda: app.main_screen.panes.io_panel.grid is not None, "the grid")
        await pilot.pause(0.3)
        area = app.query_one("#watch-area")
        assert area.has_class("-wide")  # beside the table: there is room for both
        assert not table_cut(app)
        grid = app.main_screen.panes.io_panel.grid
        assert grid is not None and grid.layout.per_line == 16
        assert grid.layout.width <= app.main_screen.panes.io_panel.scrollable_content_region.width
        await pilot.resize_terminal(200, 50)  # room for the ●/○ symbols, and no more
        await until(
            pilot,
            lambda: (
                app.main_screen.panes.io_panel.grid is not None
                and app.main_screen.panes.io_panel.grid.layout.glyph
            ),
            "the symbols",
        )
        await pilot.pause(0.3)
        grid = app.main_screen.panes.io_panel.grid
        assert grid is not None
        assert (
            app.main_screen.panes.io_panel.scrollable_content_region.width <= grid.layout.width + 1
        )
        assert not table_cut(app)


@pytest.mark.slow
async def test_the_results_are_wrapped_again_after_a_resize(tmp_path: Path) -> None:
    """RichLog keeps lines wrapped for the width they were written at: narrower, they
    were cut, and a scrollbar hid the last one."""
    from textual.widgets import RichLog

    app = make_app(tmp_path)
    async with app.run_test(size=(160, 30)) as pilot:
        await type_line(pilot, "get S 1")
        await until(pilot, lambda: "S1 = " in results_text(app), "the result")
        results = app.query_one("#results", RichLog)
        await pilot.resize_terminal(80, 30)
        await pilot.pause(0.3)
        width = results.scrollable_content_region.width
        assert all(strip.cell_length <= width for strip in results.lines), width
        assert "not a controller." in " ".join(results_text(app).split())  # all of it
        await pilot.resize_terminal(160, 30)
        await pilot.pause(0.3)
        assert any("not a controller." in strip.text for strip in results.lines)
        assert len(results.lines) <= 6  # one line each again


async def test_results_written_before_the_pane_has_a_size_are_kept_once() -> None:
    """RichLog writes what came before its first size again, itself: once each."""
    from rich.text import Text
    from textual.app import App, ComposeResult

    from rac_console.tui.results import ResultsLog

    class Pane(App[None]):
        def compose(self) -> ComposeResult:
            log = ResultsLog(id="results")
            for n in range(3):
                log.write(Text(f"entry {n} " + "word " * 30))  # before any size
            yield log

    app = Pane()
    async with app.run_test(size=(60, 20)) as pilot:
        log = app.query_one(ResultsLog)
        await until(pilot, lambda: bool(log.lines), "the entries drawn")
        await pilot.resize_terminal(100, 20)
        await pilot.pause(0.2)
        text = "\n".join(strip.text for strip in log.lines)
        assert [text.count(f"entry {n} ") for n in range(3)] == [1, 1, 1], text
        assert all(strip.cell_length <= log.scrollable_content_region.width for strip in log.lines)


@pytest.mark.slow  # 1,400 lines drawn
async def test_the_results_pane_keeps_few_of_its_lines_as_drawn() -> None:
    """RichLog keeps each line it drew, cut to the view, in a cache of 1,024 keyed by
    the line's number since it began: a pane that shows a dozen lines kept the last
    1,024 drawn (about 5 KB each, with the styled copy each holds) beside its own."""
    from rich.text import Text
    from textual.app import App, ComposeResult
    from textual.strip import Strip

    from rac_console.tui.results import MAX_LINES as KEPT_LINES
    from rac_console.tui.results import ResultsLog

    class Pane(App[None]):
        def compose(self) -> ComposeResult:
            yield ResultsLog(id="results")

    def strips_alive() -> int:
        gc.collect()
        return sum(isinstance(thing, Strip) for thing in gc.get_objects())

    app = Pane()
    async with app.run_test(size=(60, 20)) as pilot:
        log = app.query_one(ResultsLog)
        await until(pilot, lambda: log.size.height > 0, "the pane laid out")

        async def rounds(start: int, count: int) -> None:
            for n in range(start, start + count):  # ten entries at a time, each drawn
                for m in range(10):
                    log.write(Text(f"› put I 50 {n}{m}\nI50: {n} → {m}  S_OK"))
                await pilot.pause(0.05)

        await rounds(0, 30)  # 600 lines: the pane keeps its 500
        assert len(log.lines) == KEPT_LINES
        before = strips_alive()
        await rounds(30, 40)  # 800 lines more
        assert strips_alive() < before + 100, (before, strips_alive())


# ------------------------------------------------------------- frozen (F4)


@pytest.mark.slow  # 5,000 lines drawn and more
async def test_a_frozen_log_keeps_its_lines_in_view_while_the_oldest_are_dropped() -> None:
    """F4 freezes the view on the lines shown; past MAX_LINES the log drops its oldest
    lines, and the view slid down by as many (the time shown ran on while it said
    FROZEN): it stays on the same lines until they are dropped themselves."""
    from textual.app import App, ComposeResult

    class Pane(App[None]):
        def compose(self) -> ComposeResult:
            yield FrameLog()

    def flushes(count: int, start: float) -> None:
        """``count`` flushes of 250 exchanges: 500 lines, all drawn."""
        for n in range(count):
            add_exchanges(log, 250, poll=False, start=start + n)
            log.flush()

    app = Pane()
    async with app.run_test(size=(100, 20)) as pilot:
        log = app.query_one(FrameLog)
        await until(pilot, lambda: log.size.height > 0, "the log laid out")
        flushes(MAX_LINES // 500, 1_700_000_000)
        await until(pilot, lambda: log.line_count >= MAX_LINES - 500, "the log full")
        log.auto_scroll = False  # F4
        log.scroll_to(y=log.max_scroll_y - 100, animate=False, immediate=True)
        await pilot.pause()
        shown = log.lines[int(log.scroll_y)]
        for n in range(3):  # 1,500 lines more: as many of the oldest dropped
            flushes(1, 1_700_000_100 + n)
            await pilot.pause()
            assert log.lines[int(log.scroll_y)] == shown, f"the view slid after flush {n}"
