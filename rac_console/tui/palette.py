"""The command palette (Ctrl+P) in the console's language, the help and the screenshot.

:class:`ConsoleCommands` lists the console's own commands, each with its key (read
from the bindings), then Textual's own (Theme, Keys, Screenshot, Quit). A command
that is a line of the language runs as a typed line (``submit_line``: echoed, queued,
cancelled by Esc); one that needs a file name puts the line on the command line for
the user to finish. Titles and help made from names in a file or a reply are plain
text, never markup.

:class:`PaletteActions` is a mixin of the app (what it needs of it is
:class:`~rac_console.tui.host.ConsoleHost`): the help screen, and a screenshot that is
saved even with no ``~/Downloads``, written off the screen's loop.

The commands, the help and their texts are imported when the palette or the help first
opens: the app's class needs only the two classes here to be defined.
"""

from __future__ import annotations

from asyncio import Future
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from datetime import datetime
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from platformdirs import user_downloads_path
from textual.command import DiscoveryHit, Hit, Hits, Provider
from textual.content import Content
from textual.markup import escape

from ..protocol.text import terminal_safe
from .filter_line import focus_now
from .host import host_of

if TYPE_CHECKING:
    from ..commands.policy import TargetProfile
    from .command_line import CommandLine
    from .host import ConsoleHost


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


def console_commands(app: ConsoleHost) -> Iterator[PaletteCommand]:
    """The console's commands, titled for the state they would change."""
    from ..commands.language import Connect, CsvLog
    from ..commands.target import DEFAULT_PORT
    from ..present.status import label_text
    from .help_screen import key_of
    from .watch_table import WatchTable

    cls = type(app)
    paused = app.status is not None and app.status.paused
    yield PaletteCommand(
        "Resume polling" if paused else "Pause polling",
        app.action_toggle_polling,
        "poll the watched variables again" if paused else "stop polling the watched variables",
        key_of(cls, "toggle_polling"),
    )
    polls = app.frame_log.show_polls
    yield PaletteCommand(
        "Hide poll frames" if polls else "Show poll frames",
        app.action_toggle_poll_frames,
        "the frame log shows typed exchanges only" if polls else "the frame log shows polls too",
        key_of(cls, "toggle_poll_frames"),
    )
    following = app.frame_log.auto_scroll
    yield PaletteCommand(
        "Freeze log" if following else "Follow log",
        app.action_toggle_scroll,
        "stop the frame log scrolling" if following else "scroll the frame log with new frames",
        key_of(cls, "toggle_scroll"),
    )
    yield PaletteCommand(
        "Clear log", app.action_clear_log, "empty the frame log", key_of(cls, "clear_log")
    )
    grid = app.io_panel.display
    yield PaletteCommand(
        "Hide I/O grid" if grid else "Show I/O grid",
        app.action_toggle_io_grid,
        "watched IO bits as rows of the table" if grid else "watched IO bits as a grid of words",
        key_of(cls, "toggle_io_grid"),
    )
    yield PaletteCommand(
        "Hex view of frames",
        app.action_toggle_hex,
        "show or hide each frame's bytes in hex",
        key_of(cls, "toggle_hex"),
    )
    detail = app.row_detail.is_open
    yield PaletteCommand(
        "Hide row details" if detail else "Show row details",
        app.action_toggle_detail,
        "the frame log again"
        if detail
        else "the row under the table's cursor in full, a field a line",
        f"{key_of(WatchTable, 'app.toggle_detail')} in the table",
    )
    yield PaletteCommand(
        "Help", app.action_help, "keys, commands, what the status line says", key_of(cls, "help")
    )
    status = app.status
    on_sim = status is not None and status.is_simulator
    yield PaletteCommand(
        "connect sim",
        lambda: app.submit_line("connect sim", Connect(None, DEFAULT_PORT)),
        "the built-in simulator · writes open" + (" · connected now" if on_sim else ""),
    )
    for name in app.profile_names:
        line = f"connect {name}"
        profile = app.profiles.get(name)
        label = f"  ({label_text(profile.label)})" if profile and profile.label else ""
        current = status is not None and status.profile == name
        yield PaletteCommand(
            terminal_safe(line) + label,
            partial(app.submit_line, line, Connect(name, DEFAULT_PORT)),
            profile_help(profile, current),
        )
    yield PaletteCommand(
        "load FILE…",
        lambda: app.put_on_command_line("load "),
        "add a saved watch list: type its file name",
    )
    yield PaletteCommand(
        "save FILE…",
        lambda: app.put_on_command_line("save "),
        "save the watch list as TOML: type a file name",
    )
    if app.status is not None and app.status.csv_log is not None:
        yield PaletteCommand(
            "log stop",
            lambda: app.submit_line("log stop", CsvLog(None, stop=True)),
            "stop logging to the CSV file",
        )
    else:
        yield PaletteCommand(
            "log FILE.csv…",
            lambda: app.put_on_command_line("log "),
            "log the watched values to a CSV file: type its name",
        )
    yield from frame_file_commands(app)


def frame_file_commands(app: ConsoleHost) -> Iterator[PaletteCommand]:
    """``record`` and ``transcript`` from now on, or their stop: the moment worth keeping
    is rarely foreseen when the console starts."""
    from ..commands.language import FrameFile

    status = app.status
    kinds: tuple[tuple[Literal["record", "transcript"], str | None, str], ...] = (
        ("record", status.recording if status else None, "every frame as JSON lines"),
        ("transcript", status.transcribing if status else None, "a plain transcript"),
    )
    for word, running, what in kinds:
        if running is not None:
            yield PaletteCommand(
                f"{word} stop",
                partial(app.submit_line, f"{word} stop", FrameFile(word, None, stop=True)),
                f"stop writing {what} to {terminal_safe(running)}",
            )
        else:
            yield PaletteCommand(
                f"{word} FILE…",
                partial(app.put_on_command_line, f"{word} "),
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


def textual_commands(app: ConsoleHost) -> Iterator[PaletteCommand]:
    """Textual's own (Theme, Keys, Screenshot, Quit…), with a key where one runs them."""
    from .help_screen import key_of

    for command in app.get_system_commands(app.screen):
        callback = command.callback
        action = getattr(callback, "__name__", "").removeprefix("action_")
        bound_to_app = getattr(callback, "__self__", None) is app
        key = key_of(type(app), action) if bound_to_app and action else None
        yield PaletteCommand(command.title, callback, command.help, key)


#: What ``App.COMMANDS`` holds: providers, or callables that return one.
Providers = set[type[Provider] | Callable[[], type[Provider]]]


class ConsoleCommands(Provider):
    """The palette's commands: the console's own, then Textual's."""

    def _commands(self) -> list[PaletteCommand]:
        app = host_of(self.app)
        return [*console_commands(app), *textual_commands(app)]

    async def discover(self) -> Hits:
        for command in self._commands():
            yield DiscoveryHit(
                command.display(), command.run, text=command.title, help=command.help
            )

    async def search(self, query: str) -> Hits:
        matcher = self.matcher(query)
        for command in self._commands():
            score, offsets = matcher.fuzzy_search.match(matcher.query, command.title)
            if score > 0:
                yield Hit(
                    score,
                    command.display(tuple(offsets)),
                    command.run,
                    text=command.title,
                    help=command.help,
                )


def screenshot_directory() -> tuple[Path, bool]:
    """Where a screenshot goes: the Downloads folder, or the current directory when
    there is none (True when it is the fallback)."""
    try:
        downloads = user_downloads_path()
    except Exception:  # platformdirs reads the user's dirs file: never a traceback
        downloads = None
    if downloads is not None and downloads.is_dir():
        return downloads, False
    return Path.cwd(), True


class PaletteActions:
    """The help screen, the palette's line-making commands and the screenshot."""

    def action_help(self: ConsoleHost) -> None:
        """F1, ``?`` on an empty line, the palette: open the help (F1 again closes it)."""
        from ..present.help_text import help_sections
        from .help_screen import HelpScreen, console_key_groups

        if isinstance(self.screen, HelpScreen):
            self.screen.dismiss(None)
            return
        sections = help_sections(console_key_groups(type(self.screen.app)))
        command_line = self.command_line
        # Back on the command line, wherever the help was opened from.
        self.push_screen(HelpScreen(sections), lambda _: focus_now(command_line))

    def on_command_line_help_requested(self: ConsoleHost, _: CommandLine.HelpRequested) -> None:
        self.action_help()

    def put_on_command_line(self: ConsoleHost, text: str) -> None:
        """A line for the user to finish (a file name) and run with their own Enter."""
        command_line = self.command_line
        command_line.value = text
        command_line.cursor_position = len(text)
        focus_now(command_line)

    def deliver_screenshot(
        self: ConsoleHost,
        filename: str | None = None,
        path: str | None = None,
        time_format: str | None = None,
    ) -> str | None:
        """Save an SVG of the screen in Downloads, or in the current directory when
        there is no Downloads folder (Textual's own then fails), and say where once it
        is written (by the file-writing thread: a slow disk does not stop the screen)."""
        fallback = False
        if path is not None:
            directory = Path(path).expanduser()
        else:
            directory, fallback = screenshot_directory()
        stamp = datetime.now().strftime(time_format or "%Y-%m-%dT%H_%M_%S")
        target = directory / (filename or f"{self.title}_{stamp}.svg")
        svg = self.export_screenshot()
        written = self.files.run(partial(target.write_text, svg, encoding="utf-8"))
        written.add_done_callback(partial(_say_screenshot, self, target, fallback))
        return str(target)


def _say_screenshot(host: ConsoleHost, target: Path, fallback: bool, written: Future[int]) -> None:
    """Where the screenshot went, or why it did not (a notification and a line)."""
    from ..engine.events import Message

    shown = terminal_safe(str(target))
    error = None if written.cancelled() else written.exception()
    if isinstance(error, OSError):
        why = error.strerror or type(error).__name__
        host.notify(
            f"Not saved: {shown}: {why}", title="Screenshot", severity="error", markup=False
        )
        host.show(Message(f"screenshot not saved: {shown}: {why}", "error"))
        return
    if error is not None or written.cancelled():
        return  # a bug, or the console ending: nothing to say it on
    where = " (no Downloads folder: saved in the current directory)" if fallback else ""
    host.notify(f"Saved to {shown}{where}", title="Screenshot", markup=False)
    host.show(Message(f"screenshot saved to {shown}{where}"))
