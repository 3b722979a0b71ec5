"""The Textual console's app: its lifecycle, its settings and the engines' wake-up.

The console itself is a screen (:class:`~.console.ConsoleScreen`: the panes, the lines,
the keys); the app starts the engines once the first screen is painted, stops them when
it ends, keeps the settings that stay (theme, I/O grid, log toggles) and wakes the
screen when an engine publishes.
"""

from __future__ import annotations

import asyncio
import signal
import sys
from collections.abc import Callable, Sequence
from contextlib import suppress
from typing import TYPE_CHECKING, ClassVar

from textual import on
from textual.app import App, ComposeResult
from textual.binding import BindingType
from textual.message import Message as TextualMessage
from textual.timer import Timer
from textual.worker import Worker, WorkerState

from .. import __version__
from ..engine.published.feedback import Message
from ..engine.setup.where import Where
from ..present.glyphs import ascii_wanted
from ..present.heap import keep_full_collections_rare
from . import keys
from .ascii_screen import ascii_driver
from .bounded_driver import InputDropped, bounded_driver
from .console import ConsoleScreen, SettingChanged
from .file_writes import FileWrites
from .frame_log import FrameLog
from .hangup import HANGUP_STATUS, TerminalWatch
from .memory_limit import bound_memory, is_memory_error, out_of_memory
from .palette import ConsoleCommands, Providers, deliver_screenshot
from .settings import SettingsKeeper
from .watchdog import WATCH_EVERY, Watchdog

if TYPE_CHECKING:
    from ..engine import EngineLike
    from ..engine.cell.cell import Cell
    from ..engine.setup.settings import SettingsFile
    from ..present.history import History

#: In a terminal the engine starts once the first screen is painted, or after this long.
FIRST_PAINT_WAIT = 0.5


class OutboxWoke(TextualMessage):
    """The engine put something in its empty outbox (posted from the engine's thread).

    A wake still queued stands for the new one: one pending wake at most, however fast
    the engine publishes."""

    def can_replace(self, message: TextualMessage) -> bool:
        return isinstance(message, OutboxWoke)


class RacConsoleApp(App[int]):
    """Woken by the engine: its outbox's ``notify`` posts :class:`OutboxWoke`, and the
    console screen is brought up to date then, not on a timer."""

    CSS_PATH = "app.tcss"
    COMMANDS: ClassVar[Providers] = {ConsoleCommands}  # ours, then Textual's (palette.py)
    TITLE = "rac-console"
    BINDINGS: ClassVar[list[BindingType]] = keys.APP

    def __init__(
        self,
        cell: Cell | EngineLike,
        history: History,
        watch_file: str | None = None,
        profile_names: Sequence[str] = (),
        settings: SettingsFile | None = None,
    ) -> None:
        super().__init__()
        from ..engine.cell.cell import Cell

        #: The console's targets: one engine each (a plain console is a cell of one).
        self.cell = cell if isinstance(cell, Cell) else Cell.of(cell)
        self.watch_file = watch_file
        self.files = FileWrites()  # history and settings, written off the screen's loop
        #: Served to a browser (``rac-console serve``): the cell runs there, see Where.
        self.served = self.cell.where is Where.SERVED
        self.main_screen = ConsoleScreen(self.cell, history, self.files, profile_names)
        self.kept = SettingsKeeper(self, self.main_screen, settings)
        self._engine_starting: asyncio.Future[None] | None = None  # the start, on a thread
        self.terminal_watch: TerminalWatch | None = None  # in a terminal: see hangup.py
        self.watchdog: Watchdog | None = None  # once the engines run: see watchdog.py
        self.watchdog_timer: Timer | None = None
        #: Called once the first screen is painted, before the engine starts (the
        #: command line's start turns the garbage collector back on there).
        self.after_first_paint: Callable[[], object] | None = None

    def action_interrupt(self) -> None:
        """Ctrl+C, over any screen: the console's cancel (see its ``action_interrupt``)."""
        self.main_screen.action_interrupt()

    def get_default_screen(self) -> ConsoleScreen:
        return self.main_screen

    def compose(self) -> ComposeResult:
        """The console screen's layout. Textual mounts what the app composes into its
        default screen, and waits for it before it reads the first key: a key typed at
        once acts on the command line (a screen's own compose is not waited for)."""
        yield from self.main_screen.first_panes()

    async def on_mount(self) -> None:
        """The settings apply; the engines start once the first screen is painted (at
        once without a terminal)."""
        self.kept.apply()
        self.watch(self, "theme", self.kept.changed, init=False)
        for outbox in self.cell.outboxes:  # before the engines publish anything
            outbox.notify = self._wake
        console = self.main_screen
        # Focused before the first paint: a key typed as soon as the screen shows acts
        # (Up recalls, Enter submits: the cell keeps the line until the engine runs).
        console.panes.command_line.focus()
        if not self.is_headless:
            self._watch_terminal()
            # The first paint names the target ("connecting…") at once; the engine, and
            # with it the built-in simulator, starts once that is on screen.
            for member in self.cell.members:
                member.engine.publish_target()
            console.drain_outbox()
            console.refresh_table()
            self.run_worker(self._start_after_first_paint(), name="engine start")
            return
        for mounting in console.panes.mount_hidden(console):  # no screen to paint first:
            await mounting  # as the tests see it, every pane is there before the start
        await self._start_engine()

    def _watch_terminal(self) -> None:
        """The console ends when its terminal goes: a SIGHUP (a controlling terminal
        closed), or the terminal hanging up with no signal sent (see hangup.py)."""
        loop = asyncio.get_running_loop()

        def gone() -> None:
            loop.call_soon_threadsafe(self.exit, HANGUP_STATUS)

        with suppress(NotImplementedError, AttributeError, ValueError):  # Windows: none
            loop.add_signal_handler(signal.SIGHUP, self._hung_up)
        stdin = sys.__stdin__
        # Served, stdin is the pipe from rac-console serve: it hangs up when serve dies.
        watched = stdin is not None and (stdin.isatty() or self.served)
        if stdin is not None and watched and sys.platform != "win32":  # poll(): POSIX
            self.terminal_watch = TerminalWatch(stdin.fileno(), gone).start()

    def _hung_up(self) -> None:
        if self.terminal_watch is not None:
            self.terminal_watch.hung_up()
        else:
            self.exit(HANGUP_STATUS)

    async def _start_after_first_paint(self) -> None:
        """Start the engine once the screen has been painted (after-refresh callbacks
        run then), or after FIRST_PAINT_WAIT at most."""
        painted = asyncio.Event()
        self.call_after_refresh(painted.set)
        with suppress(TimeoutError):
            await asyncio.wait_for(painted.wait(), FIRST_PAINT_WAIT)
        self.main_screen.mount_hidden_panes()
        if self.after_first_paint is not None:
            self.after_first_paint()
        await self._start_engine()

    async def _start_engine(self) -> None:
        """Start the engine, then show what it published; the one timer starts."""
        self._engine_starting = asyncio.ensure_future(asyncio.to_thread(self.cell.start))
        await asyncio.shield(self._engine_starting)  # a close waits for it: see on_unmount
        console = self.main_screen
        console.drain_outbox()
        self._welcome()
        self.kept.say_problems()
        if self.watch_file:
            from ..commands.language import WatchFile

            self.cell.members[0].engine.submit_command(WatchFile("load", self.watch_file))
        console.pacing.start_clock()
        console.pacing.now()
        console.panes.command_line.focus()
        self.watchdog = Watchdog(
            console.members,
            (console.pacing.due, self.kept.due),
            console.caught_up,
            console.engine_stopped,
        )
        self.watchdog_timer = self.set_interval(WATCH_EVERY, self.watchdog.check)

    async def on_unmount(self) -> None:
        if self._engine_starting is not None:
            await self._engine_starting  # a start under way ends before the stop below
        for outbox in self.cell.outboxes:
            outbox.notify = None
        self.kept.save(at_exit=True)
        await self.files.close()  # the last save and history line are on disk
        await asyncio.to_thread(self.cell.stop)
        for state in self.main_screen.members.states.values():
            state.status = state.member.engine.outbox.drain().status or state.status

    def exit_status(self, status: int) -> int:
        """4 when the console would end with 0 but a recording stopped on the way."""
        for state in self.main_screen.members.states.values():
            if state.status is not None:
                status = state.status.exit_status(status)
        return status

    def _welcome(self) -> None:
        from ..present.banner import welcome_lines

        members = self.main_screen.members
        simulated = [m.name for m in self.cell.members if m.target.simulated]
        key = keys.key_for("next_target") or "F8"
        said = welcome_lines(self.cell.names, members.status, simulated, __version__, key)
        for line in said:
            self.main_screen.panes.results.write(line)

    def _wake(self) -> None:
        """The outbox's ``notify``, on the engine's thread: post, never wait."""
        self.post_message(OutboxWoke())

    def on_outbox_woke(self, _: OutboxWoke) -> None:
        self.main_screen.pacing.woke()

    @on(SettingChanged)
    @on(FrameLog.OptionsChanged)
    def setting_changed(self) -> None:
        self.kept.changed()

    @on(InputDropped)
    def input_dropped(self, event: InputDropped) -> None:
        """Keys or a message from the browser were dropped (a served console's bounds)."""
        from ..present.served_bounds import keys_dropped_text, sent_dropped_text

        keys_dropped, bytes_dropped = event.dropped.take()
        if bytes_dropped:
            self.main_screen.show(Message(sent_dropped_text(bytes_dropped), "error"))
        if keys_dropped:
            self.main_screen.show(Message(keys_dropped_text(keys_dropped), "error"))

    def _handle_exception(self, error: Exception) -> None:
        """A served console out of memory ends at once (see memory_limit.py): Textual's
        report of the error would allocate, and can fail there and hang the console."""
        if self.served and is_memory_error(error):
            out_of_memory()
        super()._handle_exception(error)

    @on(Worker.StateChanged)
    def worker_failed(self, event: Worker.StateChanged) -> None:
        """A bug must not end the session at the cell: say so and carry on."""
        if event.state == WorkerState.ERROR and self.is_running:
            self.main_screen.show(Message(f"internal error: {event.worker.error!r}", "error"))

    def deliver_screenshot(
        self, filename: str | None = None, path: str | None = None, time_format: str | None = None
    ) -> str | None:
        """Save an SVG of the screen in Downloads (or here when there is none); served
        to a browser, the browser gets it (Textual's own delivery), not this machine."""
        if self.served:
            return super().deliver_screenshot(filename, None, time_format)
        return deliver_screenshot(
            self, self.files, self.main_screen.show, filename, path, time_format
        )


def run_console(
    cell: Cell | EngineLike,
    history: History,
    watch_file: str | None,
    profile_names: Sequence[str] = (),
    after_first_paint: Callable[[], object] | None = None,
) -> int:
    """The console on a cell (one target: the console as it always was; an engine is
    taken as a cell of one); ``profile_names`` are the config file's targets (the
    palette's ``connect NAME`` entries); ``after_first_paint`` is called once its first
    screen is painted. Its settings are read here, before the app runs its loop (a
    console served to a browser neither reads nor writes them)."""
    from ..engine.setup.config import config_path
    from ..engine.setup.settings import SettingsFile

    served = cell.where is Where.SERVED
    settings = None if served else SettingsFile(config_path())
    app = RacConsoleApp(cell, history, watch_file, profile_names, settings=settings)
    app.kept.load(app.available_themes)
    app.after_first_paint = after_first_paint
    if ascii_wanted():  # RAC_CONSOLE_ASCII=1, or Windows' old console host
        app.driver_class = ascii_driver(app.driver_class)
    if served:  # what the browser sends is bounded (see bounded_driver.py), and memory
        app.driver_class = bounded_driver(app.driver_class)
        bound_memory()
    keep_full_collections_rare()  # the start-up's objects frozen: no key waits on a full pass
    try:
        status = app.run() or 0
    finally:
        if app.terminal_watch is not None:
            app.terminal_watch.stop()
    return app.exit_status(status)
