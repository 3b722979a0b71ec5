"""The palette's commands: the console's own, titled for the state they would change,
each with its key, then Textual's own (Theme, Keys, Screenshot, Quit).

Loaded when the palette first opens (see :mod:`.palette`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING, Literal

from textual.content import Content
from textual.markup import escape

from ..commands.language import Connect, CsvLog, FrameFile
from ..commands.target import DEFAULT_PORT
from ..present.status import label_text
from ..protocol.text import terminal_safe
from . import keys
from .row_keys import put_on_command_line

if TYPE_CHECKING:
    from ..commands.policy import TargetProfile
    from .console import ConsoleScreen


@dataclass(frozen=True)
class PaletteCommand:
    title: str  # plain text: what the palette's search matches
    run: Callable[[], object]
    help: str = ""  # fixed text of this module (Textual reads it as markup)
    key: str | None = None

    def display(self, offsets: tuple[int, ...] = ()) -> Content:
        """The title with the matched characters marked, then the key, dimmed."""
        content = Content(self.title)
        for offset in offsets:
            if offset < len(self.title) and not self.title[offset].isspace():
                content = content.stylize("reverse", offset, offset + 1)
        if self.key:
            content = Content.assemble(content, "  ", (self.key, "dim bold"))
        return content


def console_commands(console: ConsoleScreen) -> Iterator[PaletteCommand]:
    """The console's commands, titled for the state they would change."""
    paused = console.status is not None and console.status.paused
    yield PaletteCommand(
        "Resume polling" if paused else "Pause polling",
        console.action_toggle_polling,
        "poll the watched variables again" if paused else "stop polling the watched variables",
        keys.key_for("toggle_polling"),
    )
    polls = console.panes.frame_log.show_polls
    yield PaletteCommand(
        "Hide poll frames" if polls else "Show poll frames",
        console.action_toggle_poll_frames,
        "the frame log shows typed exchanges only" if polls else "the frame log shows polls too",
        keys.key_for("toggle_poll_frames"),
    )
    following = console.panes.frame_log.auto_scroll
    yield PaletteCommand(
        "Freeze log" if following else "Follow log",
        console.action_toggle_scroll,
        "stop the frame log scrolling" if following else "scroll the frame log with new frames",
        keys.key_for("toggle_scroll"),
    )
    yield PaletteCommand(
        "Clear log", console.action_clear_log, "empty the frame log", keys.key_for("clear_log")
    )
    grid = console.panes.io_panel.display
    yield PaletteCommand(
        "Hide I/O grid" if grid else "Show I/O grid",
        console.action_toggle_io_grid,
        "watched IO bits as rows of the table" if grid else "watched IO bits as a grid of words",
        keys.key_for("toggle_io_grid"),
    )
    yield PaletteCommand(
        "Hex view of frames",
        console.action_toggle_hex,
        "show or hide each frame's bytes in hex",
        keys.key_for("toggle_hex"),
    )
    detail = console.panes.row_detail.is_open
    yield PaletteCommand(
        "Hide row details" if detail else "Show row details",
        console.action_toggle_detail,
        "the frame log again"
        if detail
        else "the row under the table's cursor in full, a field a line",
        f"{keys.key_for('screen.toggle_detail', keys.WATCH_TABLE)} in the table",
    )
    yield PaletteCommand(
        "Help",
        console.action_help,
        "keys, commands, what the status line says",
        keys.key_for("help"),
    )
    status = console.status
    on_sim = status is not None and status.is_simulator
    yield PaletteCommand(
        "connect sim",
        lambda: console.submit_line("connect sim", Connect(None, DEFAULT_PORT)),
        "the built-in simulator · writes open" + (" · connected now" if on_sim else ""),
    )
    for name in console.profile_names:
        line = f"connect {name}"
        profile = console.profiles.get(name)
        label = f"  ({label_text(profile.label)})" if profile and profile.label else ""
        current = status is not None and status.profile == name
        yield PaletteCommand(
            terminal_safe(line) + label,
            partial(console.submit_line, line, Connect(name, DEFAULT_PORT)),
            profile_help(profile, current),
        )
    yield PaletteCommand(
        "load FILE…",
        lambda: put_on_command_line(console.panes, "load "),
        "add a saved watch list: type its file name",
    )
    yield PaletteCommand(
        "save FILE…",
        lambda: put_on_command_line(console.panes, "save "),
        "save the watch list as TOML: type a file name",
    )
    if console.status is not None and console.status.csv_log is not None:
        yield PaletteCommand(
            "log stop",
            lambda: console.submit_line("log stop", CsvLog(None, stop=True)),
            "stop logging to the CSV file",
        )
    else:
        yield PaletteCommand(
            "log FILE.csv…",
            lambda: put_on_command_line(console.panes, "log "),
            "log the watched values to a CSV file: type its name",
        )
    yield from frame_file_commands(console)


def frame_file_commands(console: ConsoleScreen) -> Iterator[PaletteCommand]:
    """``record`` and ``transcript`` from now on, or their stop: the moment worth keeping
    is rarely foreseen when the console starts."""

    status = console.status
    kinds: tuple[tuple[Literal["record", "transcript"], str | None, str], ...] = (
        ("record", status.recording if status else None, "every frame as JSON lines"),
        ("transcript", status.transcribing if status else None, "a plain transcript"),
    )
    for word, running, what in kinds:
        if running is not None:
            yield PaletteCommand(
                f"{word} stop",
                partial(console.submit_line, f"{word} stop", FrameFile(word, None, stop=True)),
                f"stop writing {what} to {terminal_safe(running)}",
            )
        else:
            yield PaletteCommand(
                f"{word} FILE…",
                partial(put_on_command_line, console.panes, f"{word} "),
                f"write {what} to a file from now on: type its name",
            )


def profile_help(profile: TargetProfile | None, current: bool = False) -> str:
    """``LIVE 10.0.0.5:5006 · writes confirm · allow I 100-199``: where ``connect NAME``
    goes and what it lets through, so no two targets are mixed up in the palette (as
    markup-safe text: Textual reads a hit's help as markup)."""
    if profile is None:
        return "a target profile from the config file"
    policy = profile.policy
    parts = [f"LIVE {profile.host}:{profile.port}", f"writes {policy.writes.value}"]
    if policy.allow is not None:
        parts.append("allow " + (", ".join(str(rule) for rule in policy.allow) or "nothing"))
    if current:
        parts.append("connected now")
    return escape(terminal_safe(" · ".join(parts)))


def textual_commands(screen: ConsoleScreen) -> Iterator[PaletteCommand]:
    """Textual's own (Theme, Keys, Screenshot, Quit…), with a key where one runs them."""
    app = screen.app
    for command in app.get_system_commands(screen):
        callback = command.callback
        action = getattr(callback, "__name__", "").removeprefix("action_")
        bound_to_app = getattr(callback, "__self__", None) is app
        key = keys.key_for(f"app.{action}") if bound_to_app and action else None
        yield PaletteCommand(command.title, callback, command.help, key)
