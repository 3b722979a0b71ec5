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

The commands (:mod:`.palette_commands`), the help and their texts are imported when the
palette or the help first opens: the app's class needs only the two classes here.
"""

from __future__ import annotations

from asyncio import Future
from collections.abc import Callable
from datetime import datetime
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

from platformdirs import user_downloads_path
from textual.command import DiscoveryHit, Hit, Hits, Provider

from ..protocol.text import terminal_safe
from .filter_line import focus_now
from .host import host_of

if TYPE_CHECKING:
    from .command_line import CommandLine
    from .host import ConsoleHost
    from .palette_commands import PaletteCommand


#: What ``App.COMMANDS`` holds: providers, or callables that return one.
Providers = set[type[Provider] | Callable[[], type[Provider]]]


class ConsoleCommands(Provider):
    """The palette's commands: the console's own, then Textual's."""

    def _commands(self) -> list[PaletteCommand]:
        from .palette_commands import console_commands, textual_commands

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
        sections = help_sections(console_key_groups(type(self.screen.app), self.cell_mode))
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
