"""Settings that stay: the console's theme, I/O grid and frame-log toggles, applied at
start from the config file's ``[settings]`` and saved there when they change.

The keeper compares what the console shows with what it last saved, twice a second
(so a burst of key presses is one write, and every way of changing a setting is seen:
a key, the palette, a typed ``frames on``), and once more as the console ends. It
writes only the keys changed in this session, reading the file afresh each time, so two
consoles or an editor open on the same file lose nothing of each other's. Nothing is
saved while the palette is open (the theme picker previews each theme it passes).

A problem is one line in the results, said once: a bad value at start (ignored, left in
the file), a file that cannot be written (the session goes on, its settings unsaved).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from textual.app import ScreenStackError
from textual.command import CommandPalette

from ..commands.settings import Value
from ..engine import Message
from ..engine.settings import SettingsFile
from ..protocol import InputError

if TYPE_CHECKING:
    from .app import RacConsoleApp

#: How often what is shown is compared with what was saved: at most this many writes.
SAVE_EVERY = 0.5


class SettingsKeeper:
    """The settings of ``app``, kept in ``store`` (None: not kept, as in most tests)."""

    def __init__(self, app: RacConsoleApp, store: SettingsFile | None) -> None:
        self.app = app
        self.store = store
        self._saved: dict[str, Value] = {}  # as the file holds them (or as applied)
        self._tried: dict[str, Value] | None = None  # the last state a save failed for
        self._said = False  # a failure already said
        self._problems: list[str] = []

    def current(self) -> dict[str, Value]:
        """The settings as the console shows them now."""
        app = self.app
        log = app.frame_log
        return {
            "theme": app.theme,
            # Not .display: False once the panel is being torn down (at exit).
            "io_grid": app.io_panel.styles.display != "none",
            "poll_frames": log.show_polls,
            "hex_view": log.hex_view,
            "frame_gaps": log.show_gaps,
        }

    def apply(self) -> None:
        """Read the file and apply what it holds (at mount, before anything is drawn);
        then watch for changes. Problems are said by :meth:`say_problems`."""
        if self.store is None:
            return
        app = self.app
        try:
            loaded = self.store.load(app.available_themes)
        except InputError as exc:
            self._problems = [f"settings not read, and not saved this session: {exc}"]
            self.store = None  # a file the console cannot read, it does not write
            return
        values = dict(loaded.values)
        self._problems = list(loaded.problems)
        theme = values.get("theme")
        if isinstance(theme, str):
            app.theme = theme
        log = app.frame_log
        if isinstance(shown := values.get("io_grid"), bool) and shown != self.current()["io_grid"]:
            app.action_toggle_io_grid()
        if isinstance(shown := values.get("poll_frames"), bool):
            log.show_polls = shown
        if isinstance(shown := values.get("hex_view"), bool):
            log.hex_view = shown
        if isinstance(shown := values.get("frame_gaps"), bool):
            log.show_gaps = shown
        self._saved = self.current()
        app.set_interval(SAVE_EVERY, self.check)

    def say_problems(self) -> None:
        """The start's problems, a line each in the results (after the welcome)."""
        problems, self._problems = self._problems, []
        for problem in problems:
            self.app.show(Message(problem, "error"))

    def check(self) -> None:
        """Save what changed since the last save (not while the palette is open, nor
        while the console closes: its last timer may fire with no screen left, and the
        exit saves anyway)."""
        try:
            screen = self.app.screen
        except ScreenStackError:
            return
        if not isinstance(screen, CommandPalette):
            self.save()

    def save(self, *, at_exit: bool = False) -> None:
        if self.store is None:
            return
        now = self.current()
        changed = {key: value for key, value in now.items() if self._saved.get(key) != value}
        if not changed or now == self._tried:
            return  # nothing new, or what failed last time
        try:
            self.store.save(changed)
        except InputError as exc:
            self._tried = now
            if not self._said and not at_exit:
                self._said = True
                self.app.show(
                    Message(f"settings not saved (they hold for this session): {exc}", "error")
                )
            return
        self._saved.update(changed)
        self._tried = None
