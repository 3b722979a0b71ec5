"""Settings that stay: the theme, the I/O grid and the frame log's toggles, kept in the
config file's ``[settings]`` table.

The text logic is pure (the file's text in, the new text out): it rewrites only the
``[settings]`` table's lines and keeps every other byte. The file is written atomically
(a temporary file beside it, then ``os.replace``), keeping its mode, or owner-only when
new. The console applies the settings at start and saves them when they change.
"""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import time
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any, cast

import pytest
from rich.style import Style
from textual.color import Color
from textual.command import CommandList, CommandPalette
from textual.filter import ANSIToTruecolor
from textual.widget import Widget

from rac_console.commands.settings import (
    SETTINGS_KEYS,
    read_settings,
    toml_string,
    update_settings_text,
)
from rac_console.engine import Feedback, Message
from rac_console.engine.setup.config import CONFIG_ENV, config_path
from rac_console.engine.setup.settings import SettingsFile
from rac_console.protocol import InputError, Variant
from rac_console.tui import app as app_module
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import (
    make_app,
    pause_polling,
    results_text,
    rows_read,
    stage,
    type_line,
    until,
    watch_then_pause,
)

SOURCE = "/home/op/.config/rac-console/config.toml"

PROFILES = """\
# My robots — keep this comment, and its blank line below.

[target.cell3]
host = "192.168.0.1"   # the welding cell
label = "Cell 3 — welding"
writes = "confirm"
allow = [
  "I 100-199",   # parts counters
  "IO 64-71",
]

# the bench, last
[target.bench]
host = "10.0.0.9"
"""


WIDE = (120, 40)


def parsed(text: str) -> dict[str, object]:
    return tomllib.loads(text)


# ------------------------------------------------------------ the text, pure


def test_no_settings_table_appends_one_and_keeps_every_byte_before_it() -> None:
    new = update_settings_text(PROFILES, {"theme": "textual-light"}, SOURCE)
    assert new.startswith(PROFILES)
    assert new[len(PROFILES) :] == '\n[settings]\ntheme = "textual-light"\n'
    assert parsed(new)["target"] == parsed(PROFILES)["target"]
    assert parsed(new)["settings"] == {"theme": "textual-light"}


def test_a_file_without_a_final_newline_gets_one_before_the_table() -> None:
    text = '[target.bench]\nhost = "10.0.0.9"'
    new = update_settings_text(text, {"hex_view": True}, SOURCE)
    assert new == text + "\n\n[settings]\nhex_view = true\n"


def test_an_empty_or_missing_file_gets_just_the_table() -> None:
    assert update_settings_text("", {"io_grid": False}, SOURCE) == "[settings]\nio_grid = false\n"


SETTINGS_IN_THE_MIDDLE = """\
# rac-console settings
[settings]   # kept by the console
# the look
theme = "textual-dark"  # was dark
future_key = [1,
  [2, 3]]
note = '''
[target.fake]
'''

[target.cell3]
host = "192.168.0.1"
"""


def test_a_known_key_is_replaced_in_place_with_its_comment() -> None:
    new = update_settings_text(SETTINGS_IN_THE_MIDDLE, {"theme": "textual-light"}, SOURCE)
    assert new == SETTINGS_IN_THE_MIDDLE.replace(
        'theme = "textual-dark"  # was dark', 'theme = "textual-light"  # was dark'
    )


def test_a_new_key_goes_after_the_tables_last_key_unknown_keys_and_comments_kept() -> None:
    new = update_settings_text(
        SETTINGS_IN_THE_MIDDLE, {"hex_view": True, "frame_gaps": False}, SOURCE
    )
    # A line inside a multi-line array or string is no table header.
    assert new == SETTINGS_IN_THE_MIDDLE.replace(
        "'''\n\n[target.cell3]", "'''\nhex_view = true\nframe_gaps = false\n\n[target.cell3]"
    )
    settings = parsed(new)["settings"]
    assert settings == {
        "theme": "textual-dark",
        "future_key": [1, [2, 3]],
        "note": "[target.fake]\n",
        "hex_view": True,
        "frame_gaps": False,
    }


def test_a_settings_table_last_in_the_file() -> None:
    text = '[target.bench]\nhost = "10.0.0.9"\n\n[settings]\nio_grid = true\n'
    new = update_settings_text(text, {"io_grid": False, "poll_frames": False}, SOURCE)
    assert new == '[target.bench]\nhost = "10.0.0.9"\n\n[settings]\nio_grid = false\n' + (
        "poll_frames = false\n"
    )


def test_only_newlines_end_lines_and_a_hash_in_a_string_is_no_comment() -> None:
    text = (
        '[target.cell3]\nhost = "10.0.0.1"\nlabel = "Cell 3\u2028[settings]\u2028"\n\n'
        '[settings]\ntheme = "a#b"  # c"omment\n'
    )
    new = update_settings_text(text, {"theme": "nord"}, SOURCE)
    assert new == text.replace('"a#b"', '"nord"')


def test_windows_line_ends_are_kept() -> None:
    text = PROFILES.replace("\n", "\r\n")
    new = update_settings_text(text, {"theme": "nord"}, SOURCE)
    assert new == text + '\r\n[settings]\r\ntheme = "nord"\r\n'
    again = update_settings_text(new, {"theme": "dracula"}, SOURCE)
    assert again == text + '\r\n[settings]\r\ntheme = "dracula"\r\n'


def test_strings_are_escaped_and_read_back_the_same() -> None:
    odd = 'a"b\\c\td\x1be\x7ff\u00e9'
    assert toml_string(odd) == '"a\\"b\\\\c\\td\\u001Be\\u007Ff\u00e9"'
    new = update_settings_text("", {"theme": odd}, SOURCE)
    assert parsed(new)["settings"] == {"theme": odd}


def test_a_malformed_file_is_refused_in_one_line_naming_it() -> None:
    with pytest.raises(InputError) as caught:
        update_settings_text('[target.bench]\nhost = "10.0.0.9\n', {"hex_view": True}, SOURCE)
    text = str(caught.value)
    assert "\n" not in text
    assert text.startswith(f"{SOURCE}: not valid TOML")
    assert "line 2" in text


@pytest.mark.parametrize(
    "text",
    [
        "settings = 3\n",  # not a table (an inline table or dotted keys are: test_settings_toml)
        "[[settings]]\ntheme = 'nord'\n",  # an array of tables
    ],
)
def test_settings_the_console_cannot_rewrite_safely_are_left_alone(text: str) -> None:
    with pytest.raises(InputError) as caught:
        update_settings_text(text, {"theme": "dracula"}, SOURCE)
    assert "\n" not in str(caught.value)
    assert str(caught.value).startswith(SOURCE)
    assert str(caught.value).endswith(
        "cannot be rewritten safely: write them as a [settings] table with one key = value a line"
    )


def test_a_value_over_several_lines_is_replaced_whole() -> None:
    text = '[settings]\ntheme = """\nnord"""  # multi\nio_grid = true\n'
    new = update_settings_text(text, {"theme": "dracula"}, SOURCE)
    assert new == '[settings]\ntheme = "dracula"  # multi\nio_grid = true\n'  # its comment kept


def test_a_sub_table_of_settings_is_not_the_settings_table() -> None:
    text = '[settings.look]\ntheme = "nord"\n\n[settings]\ntheme = "nord"\n'
    new = update_settings_text(text, {"theme": "dracula"}, SOURCE)
    assert new == '[settings.look]\ntheme = "nord"\n\n[settings]\ntheme = "dracula"\n'


def test_reading_keeps_good_values_and_says_each_bad_one_in_a_line() -> None:
    values, problems = read_settings(
        {
            "theme": "nord",
            "io_grid": True,
            "hex_view": "yes",
            "poll_frames": False,
            "frame_gap": True,
        },
        SOURCE,
    )
    assert values == {"theme": "nord", "io_grid": True, "poll_frames": False}
    assert len(problems) == 2
    assert all("\n" not in p and p.startswith(SOURCE) for p in problems)
    assert "hex_view" in problems[0] and "true or false" in problems[0]
    assert "frame_gap" in problems[1] and "frame_gaps" in problems[1]  # the keys it knows


def test_a_theme_the_console_does_not_have_is_said_and_ignored() -> None:
    values, problems = read_settings({"theme": "nope", "hex_view": True}, SOURCE, ["nord"])
    assert values == {"hex_view": True}
    assert problems == [
        f'{SOURCE} [settings]: theme = "nope" is no theme here: ignored (Ctrl+P, Theme lists them)'
    ]
    assert read_settings({"theme": "nord"}, SOURCE, ["nord"]) == ({"theme": "nord"}, [])


@pytest.mark.slow
def test_the_text_logic_imports_no_io_and_no_toolkit() -> None:
    probe = (
        "import sys, rac_console.commands.settings as s\n"
        "s.update_settings_text('[settings]\\n# c\\n', {'theme': 'nord'}, 'f')\n"  # tomlkit too
        "bad = [m for m in ('asyncio', 'socket', 'threading', 'textual', 'rich',"
        " 'prompt_toolkit') if m in sys.modules]\n"
        "print(','.join(bad))"
    )
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == ""


def test_the_known_keys() -> None:
    assert set(SETTINGS_KEYS) == {"theme", "io_grid", "poll_frames", "hex_view", "frame_gaps"}


# ------------------------------------------------------------------ the file


def test_saving_creates_the_directory_and_an_owner_only_file(tmp_path: Path) -> None:
    path = tmp_path / "new" / "dir" / "config.toml"
    SettingsFile(path).save({"theme": "nord"})
    assert path.read_text(encoding="utf-8") == '[settings]\ntheme = "nord"\n'
    if sys.platform != "win32":  # POSIX modes; Windows has none (see the README)
        assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert [p.name for p in path.parent.iterdir()] == ["config.toml"]  # no temporary left


def test_saving_keeps_the_files_mode_and_every_other_byte(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_bytes(PROFILES.encode("utf-8"))
    path.chmod(0o640)
    SettingsFile(path).save({"hex_view": True})
    assert path.read_bytes().decode("utf-8") == PROFILES + "\n[settings]\nhex_view = true\n"
    if sys.platform != "win32":  # POSIX modes; Windows has none (see the README)
        assert stat.S_IMODE(path.stat().st_mode) == 0o640


@pytest.mark.skipif(
    sys.platform == "win32", reason="symlinks need administrator rights or developer mode"
)
def test_saving_through_a_symlink_updates_its_target(tmp_path: Path) -> None:
    real = tmp_path / "dotfiles" / "rac.toml"
    real.parent.mkdir()
    real.write_text(PROFILES, encoding="utf-8")
    link = tmp_path / "config.toml"
    link.symlink_to(real)
    SettingsFile(link).save({"io_grid": True})
    assert link.is_symlink()
    assert real.read_text(encoding="utf-8") == PROFILES + "\n[settings]\nio_grid = true\n"


def test_loading_reads_the_settings_table(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_text(PROFILES + '\n[settings]\ntheme = "nord"\nhex_view = 1\n', encoding="utf-8")
    loaded = SettingsFile(path).load()
    assert loaded.values == {"theme": "nord"}
    assert len(loaded.problems) == 1 and "hex_view" in loaded.problems[0]
    assert SettingsFile(tmp_path / "absent.toml").load().values == {}


def test_a_directory_where_the_file_should_be_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.mkdir()
    with pytest.raises(InputError) as caught:
        SettingsFile(path).save({"theme": "nord"})
    assert "\n" not in str(caught.value) and str(path) in str(caught.value)


def test_a_file_where_the_directory_should_be_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "plain").write_text("")
    path = tmp_path / "plain" / "config.toml"
    with pytest.raises(InputError) as caught:
        SettingsFile(path).save({"theme": "nord"})
    assert "\n" not in str(caught.value) and str(path) in str(caught.value)


@pytest.mark.skipif(
    getattr(os, "geteuid", lambda: -1)() == 0, reason="root writes into a read-only directory"
)
def test_a_read_only_directory_is_one_line_and_the_file_is_untouched(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_text(PROFILES)
    tmp_path.chmod(0o500)
    try:
        with pytest.raises(InputError) as caught:
            SettingsFile(path).save({"theme": "nord"})
    finally:
        tmp_path.chmod(0o700)
    assert "\n" not in str(caught.value) and str(path) in str(caught.value)
    assert path.read_text() == PROFILES


def test_a_malformed_file_is_not_written(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_text("[target.bench\n")
    with pytest.raises(InputError):
        SettingsFile(path).save({"theme": "nord"})
    assert path.read_text() == "[target.bench\n"


# ---------------------------------------------------------------- the console


@pytest.fixture
def config(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """RAC_CONSOLE_CONFIG in tmp_path, holding the profiles."""
    path = tmp_path / "conf" / "config.toml"
    path.parent.mkdir()
    path.write_text(PROFILES)
    monkeypatch.setenv(CONFIG_ENV, str(path))
    return path


class Console(RacConsoleApp):
    """The console, noting each message its screen shows in the results."""

    CSS_PATH = Path(app_module.__file__).with_name("app.tcss")  # type: ignore[assignment]  # beside the app, not here
    said: list[str]

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        screen = self.main_screen
        shown = screen.show

        def noting(feedback: Feedback) -> None:
            if isinstance(feedback, Message):
                self.said.append(feedback.text)
            shown(feedback)

        screen.show = noting
        screen.feed.show = noting  # type: ignore[method-assign]


def console(tmp_path: Path) -> Console:
    """The console on the built-in simulator, keeping its settings where the config is."""
    base = make_app(tmp_path)
    app = Console(
        base.main_screen.members.engine,
        base.main_screen.history,
        settings=SettingsFile(config_path()),
    )
    app.said = []
    return app


def settings_lines(app: Console) -> list[str]:
    """What the console said about its settings: each a line, each on screen (where
    the results pane may wrap it: the test terminal's console is 80 columns wide)."""
    said = [text for text in app.said if "[settings]" in text or text.startswith("settings not")]
    on_screen = "".join(results_text(app).split())  # blanks aside: where it wraps, it pads
    for text in said:
        assert "\n" not in text
        assert "".join(text.split()) in on_screen, (text, on_screen)
    return said


def palette_prompts(app: RacConsoleApp) -> list[str]:
    return [str(option.prompt) for option in app.screen.query_one(CommandList).options]


async def started(pilot) -> None:
    app = pilot.app
    await until(
        pilot,
        lambda: (
            app.main_screen.status is not None and app.main_screen.status.connection == "connected"
        ),
        "the connection",
    )


@pytest.mark.slow
async def test_a_theme_chosen_in_the_palette_is_written_and_the_rest_kept(
    tmp_path: Path, config: Path
) -> None:
    config.chmod(0o640)
    app = console(tmp_path)
    async with app.run_test(size=WIDE) as pilot:
        await started(pilot)
        await pilot.press("ctrl+p")
        await until(pilot, lambda: isinstance(app.screen, CommandPalette), "the palette")
        await pilot.press(*"theme")
        await until(
            pilot,
            lambda: bool(palette_prompts(app)) and palette_prompts(app)[0].startswith("Theme"),
            "the Theme command",
        )
        palette = app.screen
        await pilot.press("enter")
        await until(
            pilot,
            lambda: isinstance(app.screen, CommandPalette) and app.screen is not palette,
            "the theme picker",
        )
        await pilot.press(*"textual-light")
        await until(
            pilot,
            lambda: bool(palette_prompts(app)) and palette_prompts(app)[0] == "textual-light",
            "textual-light in the picker",
        )
        await pilot.press("enter")
        await until(pilot, lambda: app.theme == "textual-light", "the theme")
        await until(
            pilot,
            lambda: config.read_text() != PROFILES,
            "the settings written",
        )
        assert config.read_text() == PROFILES + '\n[settings]\ntheme = "textual-light"\n'
        assert stat.S_IMODE(config.stat().st_mode) == 0o640  # the file's own
        assert settings_lines(app) == []


@pytest.mark.slow
async def test_a_restarted_console_comes_back_as_it_was_left(tmp_path: Path, config: Path) -> None:
    app = console(tmp_path)
    async with app.run_test(size=WIDE) as pilot:
        await started(pilot)
        assert (app.theme, app.main_screen.panes.io_panel.display) == ("textual-dark", False)
        log = app.main_screen.panes.frame_log
        assert (log.show_polls, log.hex_view, log.show_gaps) == (True, False, True)
        app.theme = "textual-light"
        await pilot.press("f5", "f7", "f3")
        await app.run_action("screen.toggle_frame_times")
        # Saved while the console runs, not only at the end.
        await until(pilot, lambda: "frame_gaps = false" in config.read_text(), "the save")
    text = config.read_text()
    assert text.startswith(PROFILES)
    assert tomllib.loads(text)["settings"] == {
        "theme": "textual-light",
        "io_grid": True,
        "hex_view": True,
        "poll_frames": False,
        "frame_gaps": False,
    }

    again = console(tmp_path)
    async with again.run_test(size=WIDE) as pilot:
        await started(pilot)
        assert again.theme == "textual-light"
        assert again.main_screen.panes.io_panel.display
        log = again.main_screen.panes.frame_log
        assert (log.show_polls, log.hex_view, log.show_gaps) == (False, True, False)
        assert "(IO hidden)" in str(
            again.main_screen.panes.table.border_title
        )  # the rows went to the grid
        assert settings_lines(again) == []
        await pilot.press("f7")  # and back: hex off is saved at exit at the latest
    assert tomllib.loads(config.read_text())["settings"]["hex_view"] is False
    assert config.read_text().startswith(PROFILES)


@pytest.mark.slow
async def test_a_change_undone_before_the_save_writes_nothing(tmp_path: Path, config: Path) -> None:
    app = console(tmp_path)
    async with app.run_test(size=WIDE) as pilot:
        await started(pilot)
        app.main_screen.action_toggle_hex()  # both in one go: no save can fall between them
        app.main_screen.action_toggle_hex()
        await pilot.pause()
    assert config.read_text() == PROFILES


@pytest.mark.slow
async def test_a_directory_where_the_config_should_be_is_said_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    where = tmp_path / "config.toml"
    where.mkdir()
    monkeypatch.setenv(CONFIG_ENV, str(where))
    app = console(tmp_path)
    async with app.run_test(size=WIDE) as pilot:
        await started(pilot)
        await pilot.press("f7")
        await until(pilot, lambda: bool(settings_lines(app)), "the settings line")
        await pilot.press("f7", "f3")
        await app.run_action("screen.toggle_frame_times")
        # The console goes on: a typed line still runs.
        await type_line(pilot, "get I 1")
        await until(pilot, lambda: "› get I 1" in results_text(app), "the line's result")
        lines = settings_lines(app)
        assert len(lines) == 1, lines
        assert str(where) in lines[0] and "not saved" in lines[0]
    assert where.is_dir() and not any(where.iterdir())


@pytest.mark.slow
async def test_an_unwritable_config_is_said_once_and_the_console_goes_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "plain").write_text("not a directory")
    where = tmp_path / "plain" / "config.toml"
    monkeypatch.setenv(CONFIG_ENV, str(where))
    app = console(tmp_path)
    async with app.run_test(size=WIDE) as pilot:
        await started(pilot)
        assert settings_lines(app) == []  # no file yet is no problem
        await pilot.press("f7")
        await until(pilot, lambda: bool(settings_lines(app)), "the settings line")
        await pilot.press("f5")
        await until(pilot, lambda: app.main_screen.panes.io_panel.display, "the I/O grid")
        await type_line(pilot, "get I 1")
        await until(pilot, lambda: "› get I 1" in results_text(app), "the line's result")
        assert app.main_screen.panes.frame_log.hex_view  # nothing on screen lost
        lines = settings_lines(app)
        assert len(lines) == 1, lines
        assert "settings not saved" in lines[0] and str(where) in lines[0]


@pytest.mark.slow
async def test_a_config_broken_while_the_console_runs_is_left_as_it_is(
    tmp_path: Path, config: Path
) -> None:
    app = console(tmp_path)
    async with app.run_test(size=WIDE) as pilot:
        await started(pilot)
        config.write_text(PROFILES + "[settings\n")  # the user, editing it meanwhile
        await pilot.press("f7")
        await until(pilot, lambda: bool(settings_lines(app)), "the settings line")
        await pilot.press("f3")
        await until(
            pilot, lambda: not app.main_screen.panes.frame_log.show_polls, "poll frames hidden"
        )
        await type_line(pilot, "get I 1")
        await until(pilot, lambda: "› get I 1" in results_text(app), "the line's result")
        lines = settings_lines(app)
        assert len(lines) == 1 and "not valid TOML" in lines[0] and str(config) in lines[0]
    assert config.read_text() == PROFILES + "[settings\n"


@pytest.mark.slow
async def test_bad_settings_are_ignored_with_a_line_each_and_kept_in_the_file(
    tmp_path: Path, config: Path
) -> None:
    text = PROFILES + '\n[settings]\ntheme = "no-such-theme"\nio_grid = "yes"\nhex_view = true\n'
    config.write_text(text)
    app = console(tmp_path)
    async with app.run_test(size=WIDE) as pilot:
        await started(pilot)
        await until(pilot, lambda: len(settings_lines(app)) == 2, "a line per bad setting")
        lines = settings_lines(app)
        assert "no-such-theme" in lines[0] and "ignored" in lines[0]
        assert "io_grid" in lines[1] and "ignored" in lines[1]
        assert app.theme == "textual-dark" and not app.main_screen.panes.io_panel.display
        assert app.main_screen.panes.frame_log.hex_view  # the good one applied
        await pilot.press("f3")
        await until(pilot, lambda: "poll_frames" in config.read_text(), "the save")
    # What the user wrote is kept, even the bad values: only the changed key is written.
    assert config.read_text() == text + "poll_frames = false\n"


# ------------------------------------------------- the change highlight, any theme


def contrast(one: tuple[int, int, int], other: tuple[int, int, int]) -> float:
    """WCAG's contrast ratio of two colours, 1 to 21."""

    def luminance(rgb: tuple[int, int, int]) -> float:
        def channel(value: int) -> float:
            c = value / 255
            return c / 12.92 if c <= 0.03928 else ((c + 0.055) / 1.055) ** 2.4

        r, g, b = (channel(v) for v in rgb)
        return 0.2126 * r + 0.7152 * g + 0.0722 * b

    high, low = sorted((luminance(one), luminance(other)), reverse=True)
    return (high + 0.05) / (low + 0.05)


def colours_on_screen(
    app: RacConsoleApp, widget: Widget, texts: set[str]
) -> dict[str, list[float]]:
    """The segments of ``widget`` that hold one of ``texts`` (blanks aside), each with
    the contrast of the colours the terminal gets for it: system colours as the theme's
    ANSI palette, dim blended into the background, as Textual's truecolor filter sends
    them."""
    to_truecolor = ANSIToTruecolor(app.ansi_theme)
    background = Color.parse(app.current_theme.background or "black").rich_color
    found: dict[str, list[float]] = {}
    for y in range(widget.size.height):
        for segment in widget.render_line(y):
            if (text := segment.text.strip()) not in texts:
                continue
            style = to_truecolor.truecolor_style(segment.style or Style(), background)
            assert style.color is not None and style.bgcolor is not None, segment
            fg, bg = style.color.get_truecolor(), style.bgcolor.get_truecolor()
            found.setdefault(text, []).append(contrast(fg, bg))
    return found


async def changed_just_now(pilot, rows: int) -> None:
    """Polling paused, every row stamped as changed (a minute ahead: highlighted for as
    long as the test needs, whatever the machine's speed)."""
    app = pilot.app
    await rows_read(pilot, rows)
    await pause_polling(pilot)
    ahead = time.monotonic() + 60
    for var, view in list(app.main_screen.members.rows.items()):
        app.main_screen.members.rows[var] = replace(view, changed_at=ahead)


async def each_theme(pilot):
    """Every theme the console offers, each in turn, the table and grid redrawn in it."""
    app = pilot.app
    for name in app.available_themes:
        app.theme = name
        await pilot.pause()  # the theme's CSS applied
        app.main_screen.refresh_table()
        await pilot.pause()  # the cells redrawn
        yield name


def assert_legible(name: str, found: dict[str, list[float]], texts: set[str]) -> None:
    assert set(found) == texts, (name, found)
    for text, ratios in found.items():
        assert min(ratios) >= 3, f"{name}: {text!r} at {min(ratios):.2f}:1"


@pytest.mark.slow
async def test_the_change_highlight_is_legible_in_every_theme(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(170, 30)) as pilot:
        await type_line(pilot, "watch I 4")
        await type_line(pilot, "watch IO 128-131")
        await until(pilot, lambda: len(app.main_screen.members.rows) == 5, "the rows")
        await type_line(pilot, "put IO 130 off")  # OFF and ON both
        await until(
            pilot,
            lambda: any(
                str(v) == "IO130" and r.variant and not r.variant.value
                for v, r in app.main_screen.members.rows.items()
            ),
            "IO 130 off",
        )
        await changed_just_now(pilot, rows=5)
        assert not app.available_themes["textual-light"].dark
        await pilot.press("f5")
        await until(pilot, lambda: app.main_screen.panes.io_panel.grid is not None, "the I/O grid")

        def grid_texts() -> set[str]:
            grid = app.main_screen.panes.io_panel.grid
            assert grid is not None
            word = grid.lines[0].word
            return {"128", "129", "130", "131", word.hex_text(), word.dec_text()}

        def grid_drawn() -> bool:
            """Every text of the grid on the screen (a busy machine paints it later)."""
            body = app.main_screen.panes.io_panel.query_one("#io-grid")
            return set(colours_on_screen(app, body, grid_texts())) == grid_texts()

        await until(pilot, grid_drawn, "the I/O grid drawn, its word included")
        app.main_screen.panes.table.set_hide_io(
            False
        )  # the IO rows in the table too: both in one pass
        i4 = next(row for var, row in app.main_screen.members.rows.items() if str(var) == "I4")
        in_table = {str(cast(Variant, i4.variant).value), "ON", "OFF"}
        async for name in each_theme(pilot):
            assert_legible(
                name, colours_on_screen(app, app.main_screen.panes.table, in_table), in_table
            )
            in_grid = grid_texts()
            body = app.main_screen.panes.io_panel.query_one("#io-grid")
            assert_legible(name, colours_on_screen(app, body, in_grid), in_grid)


@pytest.mark.slow
@pytest.mark.usefixtures("utc")
def test_snapshot_a_just_changed_row_in_the_light_theme(snap_compare, tmp_path: Path) -> None:
    app = make_app(tmp_path)

    async def run_before(pilot) -> None:
        app.theme = "textual-light"
        await type_line(pilot, "put IO 130 off")
        lines = ("watch P 1 pick", "watch I 4 parts", "watch IO 128-131")
        await watch_then_pause(pilot, lines, rows=6)
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "no frames flowing")
        stage(app)  # IO 128 timed out (stale)
        app.main_screen.flush_log()
        await until(
            pilot, lambda: app.main_screen.frames_per_second() == 0, "the staged frames' rate"
        )
        await pilot.press("f5")
        app.main_screen.panes.table.set_hide_io(False)  # the IO rows in the table and in the grid
        # I4, IO 130 (OFF) and IO 131 (ON) changed just now (stamped a minute ahead: for
        # as long as it takes); the others 5 s ago, as stage() had them (5.001: "5s" for the
        # whole second after, however late a busy machine draws the screen).
        now = time.monotonic()
        for var, view in list(app.main_screen.members.rows.items()):
            changed = str(var) in ("I4", "IO130", "IO131")
            app.main_screen.members.rows[var] = replace(
                view, changed_at=now + 60 if changed else now - 5.001
            )
        app.main_screen.refresh_table()
        await pilot.pause(0.1)

    assert snap_compare(app, terminal_size=(120, 34), run_before=run_before)


@pytest.mark.slow
async def test_keys_toggled_and_back_make_no_config_file(tmp_path: Path) -> None:
    """A newcomer with no config file looks at the polls and the hex, and back: no file
    appears to hold what the console would do anyway."""
    assert not config_path().exists()
    app = console(tmp_path)
    async with app.run_test(size=WIDE) as pilot:
        await started(pilot)
        await pilot.press("f3", "f5", "f7")
        # Each toggle held twice the save's half second (SAVE_AFTER), so that a save that
        # follows a change, as one does for an existing file, would have written by now.
        # The check itself is after the exit, which saves whatever is due: no wait for it.
        await pilot.pause(1.0)
        await pilot.press("f3", "f5", "f7")
        await pilot.pause(1.0)
    assert not config_path().exists()
    once = console(tmp_path)
    async with once.run_test(size=WIDE) as pilot:
        await started(pilot)
        await pilot.press("f7")  # a real change is kept: written at exit at the latest
    assert tomllib.loads(config_path().read_text())["settings"] == {"hex_view": True}
