"""The command palette (Ctrl+P), the help screen (F1, ``?``) and the palette's Screenshot.

The pure help text is tested without an app; the rest drives the console with Pilot
against the built-in simulator.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from textual.command import CommandList, CommandPalette
from textual.widgets import Input

from rac_console.engine.commands.builtin import BUILTIN
from rac_console.engine.commands.registry import RAW_HELP
from rac_console.present.help_text import (
    HelpEntry,
    HelpSection,
    filter_sections,
    help_sections,
    key_entries,
    key_label,
    plain_lines,
)
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.help_screen import HelpScreen, console_key_groups
from rac_console.tui.status_bar import StatusBar
from tests.support.drivers import make_app, results_text, type_line, until

# ------------------------------------------------------------------ the help text


@pytest.mark.parametrize(
    ("key", "label"),
    [
        ("f1", "F1"),
        ("ctrl+l", "Ctrl+L"),
        ("shift+f6", "Shift+F6"),
        ("escape", "Esc"),
        ("slash", "/"),
        ("question_mark", "?"),
        ("space", "Space"),
        ("delete", "Delete"),
        ("shift+tab", "Shift+Tab"),
        ("s", "s"),
        ("pageup", "PgUp"),
    ],
)
def test_key_labels_read_as_on_the_keyboard(key: str, label: str) -> None:
    assert key_label(key) == label


def test_keys_with_one_description_share_an_entry() -> None:
    entries = key_entries([("t", "Close trend"), ("escape", "Close trend"), ("w", "Window")])
    assert [(e.term, e.text) for e in entries] == [("t / Esc", "Close trend"), ("w", "Window")]


def test_every_command_of_the_registry_is_in_the_help_with_its_example() -> None:
    sections = help_sections([])
    commands = next(s for s in sections if s.title == "Commands")
    lines = plain_lines([commands])
    for spec in BUILTIN:
        entry = next(e for e in commands.entries if e.term == spec.usage)
        assert entry.text == spec.summary
        if spec.example:
            assert f"e.g. {spec.example}" in entry.more
    assert any(RAW_HELP in line for line in lines)


def test_the_status_line_section_explains_each_figure() -> None:
    status = next(s for s in help_sections([]) if s.title == "Status line")
    text = "\n".join(plain_lines([status]))
    for figure in (
        "SIMULATOR",
        "READ-ONLY",
        "RECORDING STOPPED",
        "CSV",
        "Esc cancels",
        "rtt",
        "polls/s",
        "cycle",
        "NOT MET",
        "frames/s",
        "POLLING PAUSED",
        "retrying",
        "profile",
        "confirm",
    ):
        assert figure in text, figure


def test_the_filter_keeps_matching_entries_case_insensitively_and_counts_them() -> None:
    sections = [
        HelpSection("A", (HelpEntry("F2", "Pause polls"), HelpEntry("F3", "Poll frames"))),
        HelpSection("B", (HelpEntry("log FILE.csv", "CSV", ("e.g. log a.csv",)),)),
    ]
    shown, matched, total = filter_sections(sections, "POLL")
    assert (matched, total) == (2, 3)
    assert [s.title for s in shown] == ["A"]
    shown, matched, _ = filter_sections(sections, "a.csv")  # the extra lines count too
    assert matched == 1 and shown[0].title == "B"
    shown, matched, _ = filter_sections(sections, "  ")
    assert matched == 3 and shown == sections


def test_the_key_groups_are_read_from_the_bindings() -> None:
    groups = dict(console_key_groups(RacConsoleApp))
    anywhere = dict(groups["anywhere"])
    assert anywhere["F1"] == "Help"
    assert anywhere["F2"] == "Pause or resume polling"  # one line for both of its words
    assert anywhere["Ctrl+P"] == "Command palette"
    assert "cancel" in anywhere["Ctrl+C"].lower() and "Ctrl+Q" in anywhere["Ctrl+C"]
    assert dict(groups["watch table (F6)"])["Space"] == "Toggle"
    assert "Toggle bit" in dict(groups["I/O grid (F5, then F6)"]).values()
    assert "Esc" in dict(groups["frame log (F6)"])
    assert dict(groups["command line"])["Tab"].startswith("Complete the command")


@pytest.mark.slow
def test_the_help_text_imports_no_terminal_toolkit() -> None:
    """Plain text for any front end: the REPL can print it without Textual or Rich."""
    probe = (
        "import sys, rac_console.present.help_text\n"
        "print(','.join(m for m in ('textual', 'rich', 'prompt_toolkit') if m in sys.modules))"
    )
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == ""


# ------------------------------------------------------------------ the palette


def app_with_profiles(tmp_path: Path, *names: str) -> RacConsoleApp:
    base = make_app(tmp_path)
    return RacConsoleApp(
        base.main_screen.members.engine, base.main_screen.history, profile_names=names
    )


def palette_prompts(app: RacConsoleApp) -> list[str]:
    return [str(option.prompt) for option in app.screen.query_one(CommandList).options]


async def open_palette(pilot, query: str = "") -> None:
    app = pilot.app
    await pilot.press("ctrl+p")
    await until(pilot, lambda: isinstance(app.screen, CommandPalette), "the palette")
    if query:
        await pilot.press(*query)
    await until(pilot, lambda: bool(palette_prompts(app)), f"the palette's hits for {query!r}")


@pytest.mark.slow
async def test_palette_pause_pauses_polling_and_the_status_line_says_so(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await until(pilot, lambda: app.main_screen.status is not None, "the first status")
        await open_palette(pilot, "pause")
        assert palette_prompts(app)[0].startswith("Pause polling")
        assert "F2" in palette_prompts(app)[0]
        await pilot.press("enter")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.paused,
            "the pause",
        )
        await until(
            pilot,
            lambda: "POLLING PAUSED" in str(app.query_one(StatusBar).render()),
            "the status line",
        )
        await open_palette(pilot, "polling")
        assert palette_prompts(app)[0].startswith("Resume polling")  # the title follows
        await pilot.press("escape")


@pytest.mark.slow
async def test_palette_lists_the_consoles_commands_with_their_keys(tmp_path: Path) -> None:
    app = app_with_profiles(tmp_path, "cell3", "[bold]odd")
    async with app.run_test(size=(100, 40)) as pilot:
        await open_palette(pilot)
        await until(pilot, lambda: len(palette_prompts(app)) > 15, "every discovery hit")
        prompts = palette_prompts(app)
        for expected in (
            "Pause polling  F2",
            "Hide poll frames  F3",
            "Freeze log  F4",
            "Clear log  Ctrl+L",
            "Show I/O grid  F5",
            "Help  F1",
            "connect sim",
            "connect cell3",
            "connect [bold]odd",  # a name from a file is text, never markup
            "load FILE",
            "save FILE",
            "log FILE.csv",
            "record stop",  # the console of the tests records to wire.jsonl
            "transcript FILE",
            "Theme",
            "Keys",
            "Screenshot",
            "Quit  Ctrl+Q",
        ):
            assert any(p.startswith(expected) for p in prompts), (expected, prompts)
        assert any(p.startswith("Hex view") for p in prompts), prompts


@pytest.mark.slow
async def test_palette_connect_sim_runs_the_line_as_typed(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await open_palette(pilot, "connect sim")
        assert palette_prompts(app)[0].startswith("connect sim")
        await pilot.press("enter")
        # Echoed in the results once its result comes back, as a typed line is.
        await until(pilot, lambda: "› connect sim" in results_text(app), "the line's echo")
        await until(
            pilot,
            lambda: "simulator" in results_text(app).partition("› connect sim")[2],
            "the line's result",
        )


@pytest.mark.slow
async def test_palette_load_puts_the_command_on_the_line_to_finish(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await open_palette(pilot, "load")
        await pilot.press("enter")
        await until(pilot, lambda: app.main_screen.panes.command_line.value == "load ", "the line")
        await until(
            pilot,
            lambda: app.focused is app.main_screen.panes.command_line,
            "the command line's focus",
        )
        assert app.main_screen.panes.command_line.cursor_position == len("load ")
        assert not app.main_screen.lines.pending  # nothing runs before the user's own Enter


@pytest.mark.slow
async def test_palette_record_starts_and_stops_recording(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    path = tmp_path / "moment.jsonl"
    async with app.run_test(size=(100, 30)) as pilot:
        await type_line(pilot, "record stop")  # the tests' own recording first
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.recording is None,
            "stopped",
        )
        await open_palette(pilot, "record")
        assert palette_prompts(app)[0].startswith("record FILE")
        await pilot.press("enter")
        await until(
            pilot, lambda: app.main_screen.panes.command_line.value == "record ", "the line"
        )
        for key in str(path):
            await pilot.press(key)
        await pilot.press("enter")
        await until(
            pilot,
            lambda: (
                app.main_screen.status is not None and app.main_screen.status.recording == str(path)
            ),
            "recording",
        )
        await open_palette(pilot, "record stop")
        assert palette_prompts(app)[0].startswith("record stop")
        await pilot.press("enter")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.recording is None,
            "stopped",
        )
    assert path.exists()


# ------------------------------------------------------------------ the help screen


def help_screen(app: RacConsoleApp) -> HelpScreen:
    screen = app.screen
    assert isinstance(screen, HelpScreen)
    return screen


@pytest.mark.slow
async def test_f1_opens_help_search_narrows_it_and_esc_returns_to_the_command_line(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("f6")  # from the table: Esc still comes back to the command line
        await pilot.press("f1")
        await until(pilot, lambda: isinstance(app.screen, HelpScreen), "the help screen")
        screen = help_screen(app)
        total = screen.matched
        assert screen.focused is screen.query_one(Input)
        assert "F2" in screen.shown_text and "put TYPE INDEX VALUE" in screen.shown_text
        await pilot.press(*"CSV")
        await until(pilot, lambda: screen.matched < total, "the filter")
        assert screen.matched > 0
        assert "csv" in screen.shown_text.lower()
        assert "Pause polls" not in screen.shown_text
        assert f"{screen.matched} of {total}" in str(screen.query_one("#help-body").border_subtitle)
        await pilot.press(*"zzzz")
        await until(pilot, lambda: screen.matched == 0, "no match")
        assert "nothing matches" in screen.shown_text
        await pilot.press("escape")
        await until(pilot, lambda: not isinstance(app.screen, HelpScreen), "the help to close")
        await until(
            pilot,
            lambda: app.focused is app.main_screen.panes.command_line,
            "the command line's focus",
        )


@pytest.mark.slow
async def test_question_mark_on_an_empty_line_opens_help_and_in_a_line_is_a_character(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("question_mark")
        await until(pilot, lambda: isinstance(app.screen, HelpScreen), "the help screen")
        assert app.screen.query_one(Input).value == ""  # the ? opened it, it was not typed
        await pilot.press("escape")
        await until(
            pilot,
            lambda: app.focused is app.main_screen.panes.command_line,
            "the command line's focus",
        )
        assert app.main_screen.panes.command_line.value == ""
        await pilot.press(*"get ?")
        await pilot.pause()
        assert app.main_screen.panes.command_line.value == "get ?"
        assert not isinstance(app.screen, HelpScreen)


@pytest.mark.slow
async def test_f1_in_the_help_closes_it(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("f1")
        await until(pilot, lambda: isinstance(app.screen, HelpScreen), "the help screen")
        await pilot.press("f1")
        await until(pilot, lambda: not isinstance(app.screen, HelpScreen), "the help to close")


@pytest.mark.slow
async def test_the_palette_over_the_help_lists_the_consoles_commands(tmp_path: Path) -> None:
    """Ctrl+P works over every screen (the help's footer offers it): its commands are
    the console's, whatever screen the palette opened over."""
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 40)) as pilot:
        await pilot.press("f1")
        await until(pilot, lambda: isinstance(app.screen, HelpScreen), "the help screen")
        await open_palette(pilot, "pause")
        assert palette_prompts(app)[0].startswith("Pause polling")
        await pilot.press("enter")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.paused,
            "the pause",
        )


@pytest.mark.slow
async def test_the_consoles_keys_wait_for_the_help_to_close(tmp_path: Path) -> None:
    """Over the help, F1 and Esc close it and Ctrl+P, Ctrl+C and Ctrl+Q work; the
    console's other keys (F2 to F8, Ctrl+L) act on the console once it is back, where
    what they change can be seen, not on a screen hidden behind the help."""
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 40)) as pilot:
        await until(pilot, lambda: app.main_screen.status is not None, "the first status")
        await pilot.press("f1")
        await until(pilot, lambda: isinstance(app.screen, HelpScreen), "the help screen")
        await pilot.press("f5", "f2")
        await pilot.press("escape")
        await until(pilot, lambda: not isinstance(app.screen, HelpScreen), "the help to close")
        await pilot.press("f5")  # the next key on the console: the grid opens now
        await until(pilot, lambda: app.main_screen.panes.io_panel.display, "the I/O grid")
        await type_line(pilot, "get I 1")  # run after any pause F2 might have sent
        await until(pilot, lambda: "› get I 1" in results_text(app), "the line's answer")
        status = app.main_screen.status
        assert status is not None and not status.paused  # F2 over the help paused nothing


@pytest.mark.slow
def test_help_screen_80x24(snap_compare, tmp_path: Path) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        await pilot.press("f1")
        await until(pilot, lambda: isinstance(app.screen, HelpScreen), "the help screen")
        app.screen.query_one(Input).cursor_blink = False
        await pilot.press(*"poll")
        await pilot.pause(0.1)

    assert snap_compare(app, terminal_size=(80, 24), run_before=run_before)


# ------------------------------------------------------------------ the screenshot


def unwrapped_results(app: RacConsoleApp) -> str:
    """The results pane with its wrapped lines joined (a long path wraps)."""
    return results_text(app).replace("\n", "")


@pytest.mark.slow
async def test_screenshot_without_downloads_goes_to_the_current_directory_and_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    assert not (Path.home() / "Downloads").exists()  # the env fixture's private HOME
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await open_palette(pilot, "screenshot")
        await pilot.press("enter")
        await until(pilot, lambda: list(work.glob("*.svg")) != [], "the screenshot file")
        (saved,) = work.glob("*.svg")
        assert saved.read_text().startswith("<svg")
        await until(pilot, lambda: str(saved) in unwrapped_results(app), "where it went")
        assert "no Downloads folder" in unwrapped_results(app)


@pytest.mark.slow
async def test_screenshot_goes_to_downloads_when_there_is_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    downloads = Path.home() / "Downloads"
    downloads.mkdir()
    monkeypatch.chdir(tmp_path)
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        app.action_screenshot()
        await until(pilot, lambda: list(downloads.glob("*.svg")) != [], "the screenshot file")
        (saved,) = downloads.glob("*.svg")
        await until(pilot, lambda: str(saved) in unwrapped_results(app), "where it went")
        assert not list(tmp_path.glob("*.svg"))
