"""The command palette (Ctrl+P) in the console's language, the help and the screenshot.

:class:`ConsoleCommands` lists the console's own commands, each with its key (read
from the bindings), then Textual's own (Theme, Keys, Screenshot, Quit). A command
that is a line of the language runs as a typed line (``submit_line``: echoed, queued,
cancelled by Esc); one that needs a file name puts the line on the command line for
the user to finish. Titles and help made from names in a file or a reply are plain
text, never markup.

:func:`deliver_screenshot` saves a screenshot even with no ``~/Downloads``, written off
the screen's loop.

The commands (:mod:`.palette_commands`), the help and their texts are imported when the
palette or the help first opens: the app needs only the provider and the screenshot here.
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
from .console import ConsoleScreen

if TYPE_CHECKING:
    from textual.app import App

    from ..engine.published.events import Feedback
    from .file_writes import FileWrites
    from .palette_commands import PaletteCommand


#: What ``App.COMMANDS`` holds: providers, or callables that return one.
Providers = set[type[Provider] | Callable[[], type[Provider]]]


class ConsoleCommands(Provider):
    """The palette's commands: the console's own, then Textual's."""

    def _commands(self) -> list[PaletteCommand]:
        from .palette_commands import console_commands, textual_commands

        # The console's, over whichever screen the palette opened (the help, a question).
        consoles = [s for s in self.app.screen_stack if isinstance(s, ConsoleScreen)]
        if not consoles:
            return []
        return [*console_commands(consoles[0]), *textual_commands(consoles[0])]

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


def deliver_screenshot(
    app: App[int],
    files: FileWrites,
    show: Callable[[Feedback], None],
    filename: str | None = None,
    path: str | None = None,
    time_format: str | None = None,
) -> str | None:
    """Save an SVG of the screen in Downloads, or in the current directory when there is
    no Downloads folder (Textual's own then fails), and say where once it is written (by
    the file-writing thread: a slow disk does not stop the screen)."""
    fallback = False
    if path is not None:
        directory = Path(path).expanduser()
    else:
        directory, fallback = screenshot_directory()
    stamp = datetime.now().strftime(time_format or "%Y-%m-%dT%H_%M_%S")
    target = directory / (filename or f"{app.title}_{stamp}.svg")
    svg = app.export_screenshot()
    written = files.run(partial(target.write_text, svg, encoding="utf-8"))
    written.add_done_callback(partial(_say_screenshot, app, show, target, fallback))
    return str(target)


def _say_screenshot(
    app: App[int],
    show: Callable[[Feedback], None],
    target: Path,
    fallback: bool,
    written: Future[int],
) -> None:
    """Where the screenshot went, or why it did not (a notification and a line)."""
    from ..engine.published.events import Message

    shown = terminal_safe(str(target))
    error = None if written.cancelled() else written.exception()
    if isinstance(error, OSError):
        why = error.strerror or type(error).__name__
        app.notify(f"Not saved: {shown}: {why}", title="Screenshot", severity="error", markup=False)
        show(Message(f"screenshot not saved: {shown}: {why}", "error"))
        return
    if error is not None or written.cancelled():
        return  # a bug, or the console ending: nothing to say it on
    where = " (no Downloads folder: saved in the current directory)" if fallback else ""
    app.notify(f"Saved to {shown}{where}", title="Screenshot", markup=False)
    show(Message(f"screenshot saved to {shown}{where}"))
