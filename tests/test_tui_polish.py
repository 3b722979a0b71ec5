"""Console polish found in a tmux pass (Pilot, built-in simulator): focus after the
confirm question, keys typed right after ``/``, a footer that fits and follows the
state, hints that fit the target, the hex view's message and column, the help."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from textual import events
from textual.pilot import Pilot
from textual.widgets import Footer
from textual.widgets._footer import FooterKey

from rac_console.commands.policy import TargetProfile, WritePolicy, Writes
from rac_console.engine import Engine
from rac_console.present.history import History
from rac_console.sim.thread import SimulatorThread
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.confirm_screen import ConfirmWriteScreen
from rac_console.tui.help_screen import HelpScreen
from tests.support.drivers import (
    REQUEST_TIMEOUT,
    answerable,
    make_app,
    results_text,
    type_line,
    until,
)

#: Terminal apps: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow


@pytest.fixture
def cell() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


def confirm_console(tmp_path: Path, cell: SimulatorThread) -> RacConsoleApp:
    """The console on a profile whose writes ask first."""
    profile = TargetProfile(
        "cell3", cell.host, cell.port, "Cell 3", "red", WritePolicy(Writes.CONFIRM)
    )
    engine = Engine(
        profile.host,
        profile.port,
        timeout=REQUEST_TIMEOUT,
        interval=0.05,
        cycles=True,
        policy=profile.policy,
        profile=profile,
        profiles={profile.name: profile},
    )
    return RacConsoleApp(engine, History(tmp_path / "history"))


async def watch_rows(pilot: Pilot, line: str, rows: int) -> None:
    app = pilot.app
    assert isinstance(app, RacConsoleApp)
    await type_line(pilot, line)
    await until(
        pilot,
        lambda: (
            len(app.main_screen.members.rows) == rows
            and all(v.variant is not None for v in app.main_screen.members.rows.values())
        ),
        f"{rows} rows with values",
    )


async def confirm_up(pilot: Pilot) -> ConfirmWriteScreen:
    app = pilot.app
    await until(pilot, lambda: isinstance(app.screen, ConfirmWriteScreen), "the question")
    screen = app.screen
    assert isinstance(screen, ConfirmWriteScreen)
    await answerable(pilot, screen)
    return screen


# ------------------------------------------------------------ 1. confirm focus


async def test_answering_the_confirm_question_gives_the_focus_back_to_the_table(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = confirm_console(tmp_path, cell)
    async with app.run_test(size=(120, 40)) as pilot:
        await until(pilot, lambda: app.main_screen.status is not None, "a status")
        await watch_rows(pilot, "watch IO 128", 1)
        await pilot.press("f6")
        assert app.focused is app.main_screen.panes.table
        await pilot.press("space")
        await confirm_up(pilot)
        await pilot.press("escape")
        await until(pilot, lambda: not isinstance(app.screen, ConfirmWriteScreen), "closed")
        await until(
            pilot, lambda: app.focused is app.main_screen.panes.table, "the table focused again"
        )
        await pilot.press("space")  # the next bit, at once: the table still has the keys
        await confirm_up(pilot)
        await pilot.press("y")
        await until(pilot, lambda: not isinstance(app.screen, ConfirmWriteScreen), "closed")
        await until(
            pilot, lambda: app.focused is app.main_screen.panes.table, "the table focused again"
        )


async def test_answering_the_confirm_question_gives_the_focus_back_to_the_grid(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = confirm_console(tmp_path, cell)
    async with app.run_test(size=(120, 40)) as pilot:
        await until(pilot, lambda: app.main_screen.status is not None, "a status")
        await watch_rows(pilot, "watch IO 128-135", 8)
        await pilot.press("f5", "f6", "f6")
        await until(
            pilot, lambda: app.focused is app.main_screen.panes.io_panel, "the grid focused"
        )
        await pilot.press("space")
        await confirm_up(pilot)
        await pilot.press("escape")
        await until(pilot, lambda: not isinstance(app.screen, ConfirmWriteScreen), "closed")
        await until(
            pilot, lambda: app.focused is app.main_screen.panes.io_panel, "the grid focused again"
        )


# ------------------------------------------------------ 2. keys after the slash


def burst(app: RacConsoleApp, *keys: str) -> None:
    """Keys as a fast typist (or a paste) sends them: all queued at once. Pilot's
    ``press`` lets the app go idle between keys, which hides a race between a key and
    the ones queued behind it."""
    driver = app._driver
    assert driver is not None
    for key in keys:
        character = "/" if key == "slash" else key
        event = events.Key(key, character)
        event.set_sender(app)
        driver.send_message(event)


async def test_a_burst_after_slash_in_the_table_all_goes_to_its_filter(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await watch_rows(pilot, "watch I 1-12", 12)
        await pilot.press("f6")
        burst(app, "slash", "i", "1")
        await until(
            pilot, lambda: app.main_screen.panes.table_filter.value == "i1", "i1 in the filter"
        )
        assert app.focused is app.main_screen.panes.table_filter
        assert app.main_screen.panes.command_line.value == ""


async def test_a_burst_after_slash_in_the_frame_log_all_goes_to_its_filter(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("f6", "f6")
        assert app.focused is app.main_screen.panes.frame_log
        burst(app, "slash", *"IO131")
        await until(
            pilot, lambda: app.main_screen.panes.log_filter.value == "IO131", "IO131 in the filter"
        )
        assert app.focused is app.main_screen.panes.log_filter


# ----------------------------------------------------------------- 3. footer


def footer_line(app: RacConsoleApp) -> str:
    """The footer as drawn: the screen's last line."""
    strips = app.screen._compositor.render_strips()
    return "".join(segment.text for segment in strips[-1])


def shown_keys(app: RacConsoleApp) -> list[str]:
    """``key description`` of each key the footer shows, the palette's last."""
    footer = app.screen.query_one(Footer)
    keys = [key for key in footer.query(FooterKey) if key.display]
    keys.sort(key=lambda key: key.has_class("-command-palette"))
    return [f"{key.key_display} {key.description}".strip() for key in keys]


async def footer_fits(pilot: Pilot, where: str) -> None:
    """The footer's line is exactly its keys, whole, one space apart, then the palette:
    nothing cut mid-word, nothing drawn over."""
    app = pilot.app
    assert isinstance(app, RacConsoleApp)
    await pilot.pause()
    await pilot.wait_for_scheduled_animations()

    def drawn() -> bool:
        keys = shown_keys(app)
        line = footer_line(app).rstrip()
        *left, palette = keys
        expected = re.escape(" ".join(left)) + r" *▏" + re.escape(palette)
        return bool(keys) and re.fullmatch(expected, line) is not None

    try:
        await until(pilot, drawn, f"the footer fitting ({where})")
    except AssertionError:
        raise AssertionError(f"{where}: {footer_line(app)!r} vs {shown_keys(app)}") from None


@pytest.mark.parametrize("size", [(80, 24), (120, 40), (200, 40)])
async def test_the_footer_shows_whole_keys_in_every_pane(
    tmp_path: Path, size: tuple[int, int]
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=size) as pilot:
        await watch_rows(pilot, "watch IO 128-129", 2)
        await footer_fits(pilot, "command line")
        await pilot.press("f6")
        assert app.focused is app.main_screen.panes.table
        await footer_fits(pilot, "table")
        await pilot.press("f6")
        assert app.focused is app.main_screen.panes.frame_log
        await footer_fits(pilot, "frame log")
        await pilot.press("f5", "f6", "f6", "f6")  # log → command line → table → grid
        await until(
            pilot, lambda: app.focused is app.main_screen.panes.io_panel, "the grid focused"
        )
        await footer_fits(pilot, "I/O grid")
        await pilot.press("escape")
        await type_line(pilot, "wait 0.5", enter=True)  # Esc cancels: one more key shown
        await footer_fits(pilot, "command line, a line running")


async def test_f2_and_f4_say_what_they_will_do(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await until(pilot, lambda: "f2 Pause polls" in shown_keys(app), "Pause polls")
        assert "f4 Freeze log" in shown_keys(app)
        await pilot.press("f2")
        await until(pilot, lambda: "f2 Resume polls" in shown_keys(app), "Resume polls")
        await pilot.press("f4")
        await until(pilot, lambda: "f4 Follow log" in shown_keys(app), "Follow log")
        await pilot.press("f2", "f4")
        await until(pilot, lambda: "f2 Pause polls" in shown_keys(app), "Pause polls again")
        await until(pilot, lambda: "f4 Freeze log" in shown_keys(app), "Freeze log again")


# ------------------------------------------------------ 6. hints on read-only


async def test_a_read_only_target_offers_no_toggle_and_no_put(tmp_path: Path) -> None:
    app = make_app(tmp_path, read_only=True)
    async with app.run_test(size=(120, 40)) as pilot:
        await watch_rows(pilot, "watch IO 128", 1)
        assert "put" not in str(app.main_screen.panes.command_line.placeholder)
        await pilot.press("f6")
        await until(pilot, lambda: "del Unwatch" in shown_keys(app), "the table's keys")
        assert not any(key.startswith("space") for key in shown_keys(app))
        await pilot.press("space")  # still says why nothing is written
        await until(pilot, lambda: "read-only" in results_text(app).lower(), "the refusal")


async def test_a_writable_target_offers_the_toggle(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await watch_rows(pilot, "watch IO 128", 1)
        assert "put IO 20 on" in str(app.main_screen.panes.command_line.placeholder)
        await pilot.press("f6")
        await until(pilot, lambda: "space Toggle" in shown_keys(app), "the toggle offered")


# ------------------------------------------------------------- 4. hex view


def last_hex_message(app: RacConsoleApp) -> str:
    """The last hex view message, unwrapped."""
    text = results_text(app)
    at = text.rfind("hex view")
    return " ".join(text[at:].split()) if at >= 0 else ""


async def test_hex_view_says_where_the_bytes_are_and_lines_them_up(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 30)) as pilot:
        await type_line(pilot, "get I 1")
        await until(pilot, lambda: "I1 =" in results_text(app), "a reply")
        await pilot.press("f7")
        await until(pilot, lambda: "hex view" in results_text(app), "the message")
        assert "under" in last_hex_message(app)
        await pilot.press("f7")
        await pilot.resize_terminal(160, 30)
        await pilot.pause()
        await type_line(pilot, "get I 2")
        await type_line(pilot, "get S 1")
        await until(pilot, lambda: "S1 =" in results_text(app), "replies")
        await pilot.press("f7")
        await until(pilot, lambda: "hex view" in last_hex_message(app), "the message")
        assert "under" not in last_hex_message(app), "\n".join(
            app.main_screen.panes.frame_log.lines
        )
        app.main_screen.flush_log()
        lines = [line for line in app.main_screen.panes.frame_log.lines if "│" in line]
        assert len(lines) >= 4
        columns = {line.index("│") for line in lines}
        assert len(columns) == 1, lines


# ------------------------------------------------------------------ 5. help


def help_screen(app: RacConsoleApp) -> HelpScreen:
    screen = app.screen
    assert isinstance(screen, HelpScreen)
    return screen


async def test_help_searches_headings_and_reads_clearly(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 40)) as pilot:
        await pilot.press("f1")
        await until(pilot, lambda: isinstance(app.screen, HelpScreen), "the help")
        shown = help_screen(app).shown_text
        assert "Left  Left" not in shown and "Right  Right" not in shown
        assert "Move the cursor" in shown
        assert "Edit put" not in shown
        body = app.screen.query_one("#help-body")
        for query, wanted in (("frame log", "Filter"), ("gap", "gap column"), ("--log", "--log")):
            search = app.screen.query_one("#help-search")
            search.value = query  # type: ignore[attr-defined]
            await until(
                pilot,
                lambda: (
                    re.search(r"\d+ of \d+ lines? match", str(body.border_subtitle)) is not None
                ),
                f"{query!r} searched",
            )
            shown = help_screen(app).shown_text
            assert wanted in shown and "nothing matches" not in shown, (query, shown)
            search.value = ""  # type: ignore[attr-defined]
            await until(pilot, lambda: "type to search" in str(body.border_subtitle), "cleared")
