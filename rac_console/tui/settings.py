"""Settings that stay: the console's theme, I/O grid and frame-log toggles, applied at
start from the config file's ``[settings]`` and saved there when they change.

Every way of changing a setting (a key, the palette, a typed ``frames on``) tells the
keeper (:meth:`SettingsKeeper.changed`); it saves :data:`SAVE_AFTER` seconds after the
last change (a burst of key presses is one write), and once more as the console ends.
It writes only the keys changed in this session, reading the file afresh each time, so
two consoles or an editor open on the same file lose nothing of each other's. Nothing
is saved while the palette is open (the theme picker previews each theme it passes).
The file is written by the console's file-writing thread, never on the screen's loop,
and read before the app runs (:meth:`SettingsKeeper.load`): the first paint is in the
theme saved, and no file is read on the screen's loop.

A problem is one line in the results, said once: a bad value at start (ignored, left in
the file), a file that cannot be written (the session goes on, its settings unsaved).
"""

from __future__ import annotations

from asyncio import Future
from collections.abc import Collection
from functools import partial
from typing import TYPE_CHECKING

from textual.app import ScreenStackError
from textual.command import CommandPalette

from ..engine.published.feedback import Message
from ..protocol.errors import InputError
from .deadline import Deadline

if TYPE_CHECKING:
    from textual.app import App

    from ..commands.settings import Value
    from ..engine.setup.settings import LoadedSettings, SettingsFile
    from .console import ConsoleScreen

#: Seconds after the last change that the settings are saved.
SAVE_AFTER = 0.5


class SettingsKeeper:
    """The settings of ``app`` and its ``console``, kept in ``store`` (None: not kept,
    as in most tests)."""

    def __init__(self, app: App[int], console: ConsoleScreen, store: SettingsFile | None) -> None:
        self.app = app
        self.console = console
        self.store = store
        self._saved: dict[str, Value] = {}  # as the file holds them (or as applied)
        self._tried: dict[str, Value] | None = None  # the last state a save failed for
        self._said = False  # a failure already said
        self._problems: list[str] = []
        #: The save after the last change (checked by the app's watchdog too).
        self.due = Deadline(app, self._save_when_due)
        self._loaded: LoadedSettings | None = None  # read by load(), applied by apply()
        self._at_start: dict[str, Value] | None = None  # as applied at mount
        self._new_file = False  # no config file at start: none is made to hold the start
        self._probed = False  # whether a new file could be written, found out once

    def load(self, themes: Collection[str]) -> None:
        """Read the file now (before the app runs: no file is read on its loop); a
        problem is kept to be said once the console has started."""
        if self.store is None:
            return
        try:
            self._new_file = not self.store.path.exists()  # read here: off the app's loop
            self._loaded = self.store.load(themes)
        except InputError as exc:
            self._problems = [f"settings not read, and not saved this session: {exc}"]
            self.store = None  # a file the console cannot read, it does not write

    def current(self) -> dict[str, Value]:
        """The settings as the console shows them now."""
        panes = self.console.panes
        log = panes.frame_log
        return {
            "theme": self.app.theme,
            # Not .display: False once the panel is being torn down (at exit).
            "io_grid": panes.io_panel.styles.display != "none",
            "poll_frames": log.show_polls,
            "hex_view": log.hex_view,
            "frame_gaps": log.show_gaps,
        }

    def apply(self) -> None:
        """Apply what the file holds (at mount, before anything is drawn; read here if
        :meth:`load` was not called); then watch for changes. Problems are said by
        :meth:`say_problems`."""
        if self._loaded is None:
            self.load(self.app.available_themes)
        loaded, self._loaded = self._loaded, None
        if self.store is None or loaded is None:
            return
        values = dict(loaded.values)
        self._problems = list(loaded.problems)
        theme = values.get("theme")
        if isinstance(theme, str):
            self.app.theme = theme
        log = self.console.panes.frame_log
        if isinstance(shown := values.get("io_grid"), bool) and shown != self.current()["io_grid"]:
            self.console.action_toggle_io_grid()
        if isinstance(shown := values.get("poll_frames"), bool):
            log.show_polls = shown
        if isinstance(shown := values.get("hex_view"), bool):
            log.hex_view = shown
        if isinstance(shown := values.get("frame_gaps"), bool):
            log.show_gaps = shown
        self._saved = self.current()
        self._at_start = dict(self._saved)

    def say_problems(self) -> None:
        """The start's problems, a line each in the results (after the welcome)."""
        problems, self._problems = self._problems, []
        for problem in problems:
            self.console.show(Message(problem, "error"))

    def changed(self) -> None:
        """A setting may have changed: save after SAVE_AFTER, unless it changes again."""
        if self.store is None:
            return
        self.due.cancel()
        self.due.arm(SAVE_AFTER)

    def _save_when_due(self) -> None:
        """Save what changed (not while the palette is open: again once it is closed;
        not while the console closes: the exit saves)."""
        try:
            screen = self.app.screen
        except ScreenStackError:
            return
        if isinstance(screen, CommandPalette):
            self.changed()
        else:
            self.save()

    def save(self, *, at_exit: bool = False) -> None:
        """Queue a write of what changed since the last save (see :class:`FileWrites`)."""
        if self.store is None:
            return
        self.due.cancel()
        now = self.current()
        changed = {key: value for key, value in now.items() if self._saved.get(key) != value}
        if not changed or now == self._tried:
            return  # nothing new, or what failed last time
        if self._new_file and (not at_exit or now == self._at_start):
            # No config file yet: one is made at the exit, and only when the settings
            # then differ from the start (keys toggled and back make none). Whether it
            # can be is found out now, and said once.
            if not at_exit and not self._probed:
                self._probed = True
                probe = self.console.files.run(self.store.can_write)
                probe.add_done_callback(partial(self._saved_or_not, now, self._saved, False))
            return
        self._new_file = False
        before = dict(self._saved)
        self._saved.update(changed)  # the next save, queued behind this, needs not repeat it
        written = self.console.files.run(partial(self.store.save, changed))
        written.add_done_callback(partial(self._saved_or_not, now, before, at_exit))

    def _saved_or_not(
        self, now: dict[str, Value], before: dict[str, Value], at_exit: bool, written: Future[None]
    ) -> None:
        """On the loop, once written: a failure is said once, and the next save tries
        again what this one could not write."""
        error = None if written.cancelled() else written.exception()
        if error is None:
            self._tried = None
            return
        self._saved = before
        self._tried = now
        if not self._said and not at_exit:
            self._said = True
            self.console.show(
                Message(f"settings not saved (they hold for this session): {error}", "error")
            )
