"""The Textual console: status line, watch table, frame log, results, command line.

Over 450 lines on purpose: this is the console's composition root, where the footer's
bindings are declared and every message between the panes and the engine is routed
(the engine's wake, a typed line, a result, a confirm question, the terminal going
away); what each pane does lives in its own module and in the mixins.
"""

from __future__ import annotations

import asyncio
import signal
import sys
import time
from collections import deque
from collections.abc import Callable, Sequence
from contextlib import suppress
from functools import partial
from typing import TYPE_CHECKING, ClassVar

from rich.text import Text
from textual import on
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal
from textual.message import Message as TextualMessage
from textual.reactive import reactive
from textual.timer import Timer
from textual.widget import AwaitMount
from textual.widgets import Input, Static
from textual.worker import Worker, WorkerState

from .. import __version__
from ..engine.feedback import Message, UiStep
from ..present.cell_view import cell_targets
from ..present.glyphs import ascii_wanted
from ..present.heap import keep_full_collections_rare
from ..present.history import is_refused
from ..present.status import connect_targets, target_label
from ..protocol.text import counted, terminal_safe
from .ascii_screen import ascii_driver
from .cell_state import CellMembers, MemberState
from .command_line import CommandLine
from .file_writes import FileWrites
from .footer import FittingFooter
from .frame_log import FrameLog, log_filter_line
from .hangup import HANGUP_STATUS, TerminalWatch
from .io_panel import IoPanel, WatchArea
from .log_actions import LogActions
from .palette import ConsoleCommands, PaletteActions, Providers
from .results import ResultsLog
from .row_detail import RowDetail
from .settings import SettingsKeeper
from .status_bar import StatusBar
from .table_actions import TableActions, placeholder_for, toggle
from .trend_view import TrendView
from .watch_table import TableFilter, WatchTable, writes_refused

if TYPE_CHECKING:  # what the first paint does not need loads when first used, after it
    from ..commands.language import Command
    from ..engine import Engine
    from ..engine.cell import Cell
    from ..engine.events import ConfirmWrite, Feedback, Result
    from ..engine.outbox import Batch
    from ..engine.settings import SettingsFile
    from ..engine.status import Status
    from ..present.history import History

#: Under a flood of frames the screen is brought up to date at most this often; the
#: drains in between are put off by a one-shot timer, so keys are answered meanwhile.
MIN_DRAIN_GAP = 1 / 30
#: Under a flood (updates back to back), the costly parts wait their turn: the log is
#: written at most this often, and the table's rows rebuilt at most this often, so
#: the keys typed meanwhile are answered (the repaint budget). The last state always
#: shows: an update put off is made when its turn comes.
LOG_EVERY_UNDER_FLOOD = 1 / 10
TABLE_EVERY_UNDER_FLOOD = 1 / 5
#: The clock's tick: what changes with time alone (row ages, the retry countdown, how
#: long a reply or a line has been waited for, the frame rate) is shown in tenths.
CLOCK_EVERY = 0.2
#: The frame rate on the status line counts the frames drawn in this many seconds.
RATE_WINDOW = 2.0
#: In a terminal the engine starts once the first screen is painted, or after this long.
FIRST_PAINT_WAIT = 0.5


class OutboxWoke(TextualMessage):
    """The engine put something in its empty outbox (posted from the engine's thread).

    A wake still queued stands for the new one: one pending wake at most, however fast
    the engine publishes."""

    def can_replace(self, message: TextualMessage) -> bool:
        return isinstance(message, OutboxWoke)


PAUSE_HELP = "Pause or resume polling"
PANES_HELP = "Next or previous pane: command line, table, I/O grid, frame log"
FREEZE_HELP = "Freeze the log's scrolling, or follow new frames again"


class RacConsoleApp(CellMembers, PaletteActions, TableActions, LogActions, App[int]):
    """Woken by the engine: its outbox's ``notify`` posts :class:`OutboxWoke`, and the
    screen is brought up to date then (see :meth:`on_outbox_woke`), not on a timer."""

    CSS_PATH = "app.tcss"
    COMMANDS: ClassVar[Providers] = {ConsoleCommands}  # ours, then Textual's (palette.py)
    TITLE = "rac-console"
    BINDINGS: ClassVar[list[BindingType]] = [
        # In the footer in this order, after the focused pane's keys, as many as fit.
        Binding(
            "escape",
            "cancel_command",
            "Cancel command",
            tooltip="Cancel the running line, and the lines typed behind it",
            id="cancel-command",
        ),
        Binding("f1", "help", "Help", id="help"),
        # A cell's: shown only with more than one target (check_action).
        Binding(
            "f8",
            "next_target",
            "Next target",
            tooltip="A cell: use the next target (lines without @NAME go to it)",
            id="next-target",
        ),
        # Priority: taken as the key arrives, so the keys typed right after it go to the
        # new pane (without it they were already on their way to the old one).
        Binding(
            "f6",
            "focus_pane(1)",
            "Next pane",
            tooltip=PANES_HELP,
            id="next-pane",
            priority=True,
        ),
        # F2 and F4 say what they will do: check_action shows one of each pair.
        # The tooltip is the help screen's line (one for both keys of a pair).
        Binding("f2", "toggle_polling", "Pause polls", tooltip=PAUSE_HELP, id="toggle-polling"),
        Binding(
            "f2",
            "toggle_polling('resume')",
            "Resume polls",
            tooltip=PAUSE_HELP,
            id="resume-polling",
        ),
        Binding("f4", "toggle_scroll", "Freeze log", tooltip=FREEZE_HELP, id="toggle-scroll"),
        Binding(
            "f4", "toggle_scroll('follow')", "Follow log", tooltip=FREEZE_HELP, id="follow-log"
        ),
        Binding("ctrl+q", "quit", "Quit", id="quit", priority=True),
        Binding(
            "f5",
            "toggle_io_grid",
            "I/O grid",
            tooltip="Show or hide the I/O grid: watched IO bits as words",
            id="toggle-io-grid",
        ),
        Binding(
            "f3",
            "toggle_poll_frames",
            "Poll frames",
            tooltip="Show or hide poll frames in the log",
            id="toggle-poll-frames",
        ),
        Binding(
            "f7",
            "toggle_hex",
            "Hex view",
            tooltip="Show or hide each frame's bytes in hex in the log",
            id="toggle-hex",
        ),
        Binding("ctrl+l", "clear_log", "Clear log", id="clear-log"),
        Binding(
            "shift+f6",
            "focus_pane(-1)",
            "Previous pane",
            tooltip=PANES_HELP,
            show=False,
            id="previous-pane",
            priority=True,
        ),
        # Priority: before the command line's copy, which took it and did nothing. It
        # cancels as Esc does, from any pane, as in the REPL and the CLI.
        Binding(
            "ctrl+c",
            "interrupt",
            "Cancel command",
            tooltip="Cancel the running line, as Esc does (nothing running: it says Ctrl+Q quits)",
            show=False,
            id="interrupt",
            priority=True,
        ),
    ]

    # What the footer's keys depend on (check_action), set in one place: sync_bindings.
    line_running = reactive(False, bindings=True)  # Esc cancels it
    polling_paused = reactive(False, bindings=True)  # F2 resumes
    log_frozen = reactive(False, bindings=True)  # F4 follows

    def __init__(
        self,
        cell: Cell | Engine,
        history: History,
        watch_file: str | None = None,
        profile_names: Sequence[str] = (),
        settings: SettingsFile | None = None,
    ) -> None:
        super().__init__()
        from ..engine.cell import Cell

        #: The console's targets: one engine each (a plain console is a cell of one).
        self.cell = cell if isinstance(cell, Cell) else Cell.of(cell)
        self.states = {member.name: MemberState(member) for member in self.cell.members}
        self.cell_mode = len(self.cell.members) > 1
        self.history = history
        self.watch_file = watch_file
        self.profile_names = tuple(profile_names)  # the palette offers connect NAME
        self.profiles = dict(self.engine.profiles)  # read before the engine starts: its words
        self.files = FileWrites()  # history and settings, written off this loop
        self.kept = SettingsKeeper(self, settings)  # theme, I/O grid, log toggles
        #: Lines handed to the engine and not answered yet: seq -> (line, when), in order.
        self.lines_pending: dict[int, tuple[str, float]] = {}
        self._flushes: deque[tuple[float, int]] = deque()  # (when, frames) in RATE_WINDOW
        self._last_drain = 0.0  # time.monotonic() of the last update
        self._log_at = self._table_at = 0.0  # of the last log write and table refresh
        self._drain_due: Timer | None = None  # the put-off update, under a flood
        self._clock: Timer | None = None
        self._engine_starting: asyncio.Future[None] | None = None  # the start, on a thread
        self._status_line = Text()
        # Kept as attributes: timers and workers never query a DOM being torn down.
        self.status_bar = StatusBar(id="status")
        self.table = WatchTable(
            self.trend_store,
            self.type_on_command_line,
            self.toggle_row,
            [(state.name, state.colour) for state in self.states.values()]
            if self.cell_mode
            else (),
            id="watch",
        )
        self.table_filter = TableFilter(self.table, id="table-filter")
        self.trend_view = TrendView(self.trend_store, id="trend")
        self.row_detail = RowDetail(id="detail")
        self.frame_log = FrameLog(id="log")
        if self.cell_mode:
            self.frame_log.target_width = max(len(terminal_safe(n)) for n in self.cell.names)
        self.log_filter = log_filter_line(self.frame_log, cell=self.cell_mode)
        self.io_panel = IoPanel(lambda var: self.toggles.busy(var), id="io")
        self.watch_area = WatchArea(self.table, self.io_panel, id="watch-area")
        self.completions = Static(id="completions")
        self.hint = Static(id="hint")
        self.results = ResultsLog(id="results")
        self.command_line = CommandLine(
            self.history,
            self._completion_indices,
            id="command",
            placeholder=placeholder_for(None),
        )
        self.command_line.targets = tuple(connect_targets(self.engine.profiles))
        self.command_line.cell = tuple(cell_targets(self.cell))  # none for one target
        self.prompt = Static(id="prompt")
        self.command_line.may_ask = self.may_ask
        #: The line whose question keys typed ahead must not answer (see CommandLine).
        self._held_seq: int | None = None
        self.terminal_watch: TerminalWatch | None = None  # in a terminal: see hangup.py
        #: Called once the first screen is painted, before the engine starts (the
        #: command line's start turns the garbage collector back on there).
        self.after_first_paint: Callable[[], object] | None = None
        self._hidden_mounted = False

    def compose(self) -> ComposeResult:
        """What the first screen shows; the panes hidden at start join it later (see
        :meth:`mount_hidden_panes`)."""
        yield self.status_bar
        yield self.watch_area  # the table and the I/O grid
        yield self.frame_log
        yield self.results
        if self.cell_mode:  # the prompt names the target a line without @NAME goes to
            with Horizontal(id="command-row"):
                yield self.prompt
                yield self.command_line
        else:
            yield self.command_line
        yield FittingFooter()

    def action_next_target(self) -> None:
        """F8: ``use`` the next target of the cell, as typed."""
        from ..commands.language import Use

        names = self.cell.names
        following = names[(names.index(self.cell.current) + 1) % len(names)]
        self.submit_line(f"use {following}", Use(following))

    def mount_hidden_panes(self) -> list[AwaitMount]:
        """The panes nobody sees at start (the filter lines, the trend, the detail, the
        completions, the hint), in their places: mounted once the first screen is
        painted, which they are not on, or at once by a key that opens one before that.
        Returns what to await for them to be mounted (nothing once they are)."""
        if self._hidden_mounted:
            return []
        self._hidden_mounted = True
        return [
            self.mount(self.table_filter, after=self.watch_area),
            self.mount(
                self.log_filter,
                self.trend_view,
                self.row_detail,
                self.completions,
                after=self.frame_log,
            ),
            self.mount(self.hint, after=self.results),
        ]

    async def on_mount(self) -> None:
        self.kept.apply()
        self.watch(self, "theme", self.kept.changed, init=False)
        for outbox in self.cell.outboxes:  # before the engines publish anything
            outbox.notify = self._wake
        self.show_prompt()
        # Focused before the first paint: a key typed as soon as the screen shows acts
        # (Up recalls, Enter submits: the cell keeps the line until the engine runs).
        self.command_line.focus()
        if not self.is_headless:
            self._watch_terminal()
            # The first paint names the target ("connecting…") at once; the engine, and
            # with it the built-in simulator, starts once that is on screen.
            for member in self.cell.members:
                member.engine.publish_target()
            self.drain_outbox()
            self.refresh_table()
            self.run_worker(self._start_after_first_paint(), name="engine start")
            return
        for mounting in self.mount_hidden_panes():  # no screen to paint first: as the
            await mounting  # tests see it, every pane is there before the engine starts
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
        if stdin is not None and stdin.isatty() and sys.platform != "win32":  # poll(): POSIX
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
        self.mount_hidden_panes()
        if self.after_first_paint is not None:
            self.after_first_paint()
        await self._start_engine()

    async def _start_engine(self) -> None:
        """Start the engine, then show what it published; the one timer starts."""
        self._engine_starting = asyncio.ensure_future(asyncio.to_thread(self.cell.start))
        await asyncio.shield(self._engine_starting)  # a close waits for it: see on_unmount
        self.drain_outbox()
        self._welcome()
        self.kept.say_problems()
        if self.watch_file:
            from ..commands.language import WatchFile

            self.engine.submit_command(WatchFile("load", self.watch_file))
        # The one timer left: nothing comes from the engine while a reply, a retry or a
        # typed line is waited for, or while polling is paused, yet their clocks and the
        # rows' ages must go on. Paused when no clock is shown (see tick_clock).
        self._clock = self.set_interval(CLOCK_EVERY, self.tick_clock)
        self.update_screen()
        self.command_line.focus()

    async def on_unmount(self) -> None:
        if self._engine_starting is not None:
            await self._engine_starting  # a start under way ends before the stop below
        for outbox in self.cell.outboxes:
            outbox.notify = None
        self.kept.save(at_exit=True)
        await self.files.close()  # the last save and history line are on disk
        await asyncio.to_thread(self.cell.stop)
        for state in self.states.values():
            state.status = state.member.engine.outbox.drain().status or state.status

    def exit_status(self, status: int) -> int:
        """4 when the console would end with 0 but a recording stopped on the way."""
        for state in self.states.values():
            if state.status is not None:
                status = state.status.exit_status(status)
        return status

    def _welcome(self) -> None:
        from ..engine import SIMULATOR_NOTICE
        from ..present.banner import cell_banner, live_banner, simulated_banner
        from .help_screen import key_of

        results = self.results
        status = self.status
        if self.cell_mode:
            key = key_of(type(self), "next_target") or "F8"
            results.write(cell_banner(self.cell.names, key))
            simulated = [m.name for m in self.cell.members if m.target.simulated]
            if simulated:
                results.write(simulated_banner(simulated))
        elif status is not None and status.is_simulator:
            results.write(
                Text.assemble(
                    ("SIMULATOR", "bold black on yellow"),
                    f" {SIMULATOR_NOTICE}.",
                )
            )
        elif status is not None:
            results.write(live_banner(status))
        results.write(
            Text(
                f"rac-console {__version__}: type help, or try watch P 0, watch IO 0-7, get S 1",
                style="dim",
            )
        )

    def _completion_indices(self) -> frozenset[tuple[str, int]]:
        """Indices used or watched (the engine counts watched ones as used)."""
        return self.status.seen if self.status is not None else frozenset()

    # -------------------------------------------------------------- refresh

    def _wake(self) -> None:
        """The outbox's ``notify``, on the engine's thread: post, never wait."""
        self.post_message(OutboxWoke())

    def on_outbox_woke(self, _: OutboxWoke) -> None:
        """Bring the screen up to date now, or, under a flood, once MIN_DRAIN_GAP has
        passed since the last time (one update put off at a time)."""
        if self._drain_due is not None:
            return  # an update is due already: it takes this wake's events too
        wait = self._last_drain + MIN_DRAIN_GAP - time.monotonic()
        if wait > 0:
            self._drain_due = self.set_timer(wait, self._drain_when_due)
        else:
            self.update_screen()

    def _drain_when_due(self) -> None:
        self._drain_due = None
        self.update_screen()

    def update_screen(self) -> None:
        """Everything the engine published, on screen: results, frames, rows, status.
        Under a flood the log and the table wait their turn (see LOG_EVERY_UNDER_FLOOD)."""
        now = time.monotonic()
        flooded = now - self._last_drain < LOG_EVERY_UNDER_FLOOD
        self._last_drain = now
        self.drain_outbox()
        # The table is refreshed only with the log: a row never shows what the log has
        # not said yet (a reconnect's row before the note of it).
        log_turn = self._log_at + LOG_EVERY_UNDER_FLOOD
        table_turn = self._table_at + TABLE_EVERY_UNDER_FLOOD
        if flooded and now < log_turn:
            put_off = log_turn - now
        else:
            self._log_at = now
            self.flush_log()
            if flooded and now < table_turn:
                put_off = table_turn - now
            else:
                put_off = 0.0
                self.refresh_table()
        if put_off and self._drain_due is None:
            self._drain_due = self.set_timer(put_off, self._drain_when_due)

    def tick_clock(self) -> None:
        """The clock timer: what changes with time alone. It pauses itself when nothing
        shown counts time, and :meth:`refresh_table` starts it again."""
        self.refresh_table()
        if self._clock is not None and not self._clock_shown():
            self._clock.pause()

    def _clock_shown(self) -> bool:
        """Whether anything on screen changes with time alone."""
        return bool(
            self.members_timed()  # rows' ages, a reply waited for, a retry's countdown
            or self.lines_pending  # the running line's time
            or self.frames_per_second() > 0  # the rate, back to 0
        )

    def sync_bindings(self) -> None:
        """The one place the state the footer's keys depend on is set: a change shows
        the keys again (reactive ``bindings=True``)."""
        status = self.status
        self.line_running = bool(self.lines_pending)
        self.polling_paused = status is not None and status.paused
        self.log_frozen = not self.frame_log.auto_scroll
        self.table.refuses_writes = writes_refused(status)

    def drain_outbox(self) -> None:
        """Take everything the engines published since the last tick, in order: the
        cell's own results, then each target's batch."""
        for name, batch in self.cell.drain():
            self._take_batch(None if name is None else self.states[name], batch)
        self.show_prompt()
        self.sync_bindings()

    def _take_batch(self, state: MemberState | None, batch: Batch) -> None:
        """One target's batch (``state`` None: the cell's own answers)."""
        if state is not None and batch.status is not None:
            self._take_status(state, batch.status)
        if state is not None:
            batch.apply_rows(state.rows)
            state.removed |= batch.removed
            self.forget_rows(batch.removed - batch.rows.keys(), state.name)
            state.removed -= batch.rows.keys()
        name = state.name if state is not None and self.cell_mode else None
        if batch.events:  # none before the engines start: the first paint loads no event
            from ..engine.events import Alert, ConfirmWrite, Cycle, Result
        for event in batch.events:
            if isinstance(event, Result):
                if event.line is not None:  # a typed line: kept by the history unless refused
                    self.files.run(
                        partial(self.history.settle, event.line, refused=is_refused(event))
                    )
                self._close_question(event.seq)
                if event.seq == self._held_seq:
                    self._release_keys()
                self.lines_pending.pop(event.seq, None)
                self.take_result(event, state.name if state is not None else None)
                self._show_result(event, name)
            elif isinstance(event, Cycle):
                if state is not None:
                    self.take_cycle(event, state.name)
            elif isinstance(event, ConfirmWrite):
                self.confirm_write(event, state.name if state is not None else None)
            else:
                self.frame_log.add(event, name)
                if isinstance(event, Alert):
                    text = event.text if name is None else f"{name}: {event.text}"
                    self.show(Message(text, "error" if event.local_failure else "info"))
        if batch.frames_dropped or batch.cycles_dropped:
            lost = [
                counted(n, what)
                for n, what in (
                    (batch.frames_dropped, "frame"),
                    (batch.cycles_dropped, "poll cycle"),
                )
                if n
            ]
            from ..engine.events import Alert

            self.frame_log.add(Alert(f"{' and '.join(lost)} not shown: the screen fell behind"))

    def _take_status(self, state: MemberState, status: Status) -> None:
        old = state.status
        if old is not None and status.target_id != old.target_id:
            state.trends.clear()  # the last target's samples are not the new one's
        state.status = status
        if self.cell_mode:
            self.frame_log.slow_after = (
                max(s.status.timeout for s in self.states.values() if s.status) / 2
            )
            if old is None:
                self.sub_title = terminal_safe(f"cell: {', '.join(self.cell.names)}")
            return
        if old is None or status.target != old.target:
            self.sub_title = terminal_safe(status.target)
        if old is None or _shown_target(status) != _shown_target(old):
            self.show_target(status)
        self.follow_status(old, status)
        self.frame_log.slow_after = status.timeout / 2  # a slow reply stands out

    def flush_log(self) -> None:
        count = self.frame_log.flush()
        if count:
            self._flushes.append((time.monotonic(), count))

    def frames_per_second(self) -> float:
        """Frames drawn in the last RATE_WINDOW seconds, per second."""
        flushes = self._flushes
        since = time.monotonic() - RATE_WINDOW
        while flushes and flushes[0][0] < since:
            flushes.popleft()
        return sum(count for _, count in flushes) / RATE_WINDOW

    def refresh_table(self) -> None:
        self._table_at = time.monotonic()
        if self._clock is not None and self._clock_shown():
            self._clock.resume()
        if self.cell_mode and self.table.io_target != self.cell.current:
            self.table.io_target = self.cell.current  # the grid shows the current's IO
            self.table.set_hide_io(self.io_panel.display)
        self.table.refresh_rows(self.row_groups(), self.take_removed(), time.monotonic())
        self.redraw_trend()
        self.show_detail()
        self.io_panel.refresh_rows(self.rows, time.monotonic())
        self.watch_area.share_width()  # the grid beside the table only while both fit
        if self.cell_mode:
            self._status_line = self.status_bar.show_cell(self.badges(), self._running_line())
            return
        if self.status is None:
            return
        self._status_line = self.status_bar.show(  # for its width; repainted if changed
            self.status,
            self.engine.outbox.waiting_since,
            self.frames_per_second(),
            running=self._running_line(),
        )

    # ------------------------------------------------------------- commands

    @on(CommandLine.Entered)
    def entered(self, event: CommandLine.Entered) -> None:
        """Hand the line to the engine: lines run one at a time, each once, in order."""
        self.completions.remove_class("-visible")
        if not event.line.strip():
            if event.held:
                self.command_line.post_message(CommandLine.Release())
            return
        self.command_line.remember(event.line)
        queued = bool(self.lines_pending)
        seq = self.submit_line(event.line)
        if event.held:
            self.hold_keys(seq, queued)

    def may_ask(self, line: str) -> bool:
        """Whether this line, run now, may stop to ask before it writes: a write on a
        ``confirm`` target with nothing running before it (a write queued behind a
        long wait must not hold the keys typed meanwhile)."""
        from ..present.type_ahead import written_target

        if self.lines_pending:
            return False
        name = written_target(line, self.cell.names, self.cell.current)
        status = self.state_of(name).status if name is not None else None
        return status is not None and status.writes == "confirm" and not writes_refused(status)

    def hold_keys(self, seq: int, queued: bool) -> None:
        """The keys typed after line ``seq`` are held until it asked or ended; a line that
        turned out to be queued behind another holds none."""
        if queued or self._held_seq is not None:
            self.command_line.post_message(CommandLine.Release())
        else:
            self._held_seq = seq

    def _release_keys(self) -> None:
        self._held_seq = None
        self.command_line.post_message(CommandLine.Release())

    @on(CommandLine.Dropped)
    def keys_dropped(self, event: CommandLine.Dropped) -> None:
        keys = (
            "1 key typed ahead of the question was"
            if event.count == 1
            else f"{event.count} keys typed ahead of the question were"
        )
        self.show(Message(f"{keys} ignored: nothing typed before a question answers it"))

    def submit_line(
        self, line: str, command: Command | None = None, target: str | None = None
    ) -> int:
        """Every line the console hands the cell (typed, or made by a key on a row:
        then ``command`` is run as it is on ``target`` (None: the current one), never
        parsed, and ``line`` shows it): counted as running or queued until its result,
        and cancelled by Esc."""
        cell = self.cell
        seq = cell.submit(line) if command is None else cell.submit_command(command, line, target)
        self.lines_pending[seq] = (line, time.monotonic())
        self.sync_bindings()
        if self._clock is not None:
            self._clock.resume()  # the running line's time
        return seq

    def _running_line(self) -> tuple[str, float, int] | None:
        """The oldest line not answered yet (the one running: lines run in order), how
        long ago it was typed, and how many wait behind it."""
        if not self.lines_pending:
            return None
        line, since = next(iter(self.lines_pending.values()))
        return line, time.monotonic() - since, len(self.lines_pending) - 1

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Esc cancels only while a typed line is running (elsewhere it leaves a pane);
        F2 and F4 show the one of their pair that says what they will do."""
        if action == "cancel_command":
            return self.line_running
        if action == "next_target":
            return self.cell_mode
        if action == "toggle_polling":
            return self.polling_paused == (parameters == ("resume",))
        if action == "toggle_scroll":
            return self.log_frozen == (parameters == ("follow",))
        return True

    def action_cancel_command(self) -> None:
        """Esc: the running line ends (a wait, a latency run, a request in flight), and
        the lines typed behind it are not run."""
        if self.lines_pending:
            self.cell.cancel(queued=True)

    def action_interrupt(self) -> None:
        """Ctrl+C: cancel as Esc does. With nothing running, text selected in the
        command line (or on screen) is copied, as Textual does; else it says how to
        quit, for the hand that reached for Ctrl+C to leave."""
        if self.lines_pending:
            self.cell.cancel(queued=True)
            return
        focused = self.focused
        if isinstance(focused, Input) and focused.selected_text:
            focused.action_copy()
            return
        selected = self.screen.get_selected_text()
        if selected:
            self.copy_to_clipboard(selected)
            return
        from .help_screen import key_of

        quit_key = key_of(type(self), "quit") or "Ctrl+Q"
        self.notify(
            f"Nothing is running to cancel. {quit_key} quits.",
            title="Ctrl+C",
            markup=False,
        )

    def _show_result(self, result: Result, target: str | None = None) -> None:
        """The line echoed, then what came of it; in a cell, after the target it ran
        on (``robotB › put I 10 5``: an ``@robotB`` is said by the name)."""
        from ..present.render import echo_text

        if result.line is not None:
            self.results.write(echo_text(result.line, target))
        for feedback in result.feedback:
            self.show(feedback)

    @on(CommandLine.Completions)
    def list_completions(self, event: CommandLine.Completions) -> None:
        from ..present.completion import shown_candidates

        shown, more = shown_candidates(event.candidates)
        self.mount_hidden_panes()
        width = max(len(c.text) for c in shown)
        text = Text()
        for n, candidate in enumerate(shown):
            if n:
                text.append("\n")
            text.append(f"{candidate.text:<{width}}", style="bold")
            text.append(f"  {candidate.help}", style="dim")
        if more:
            text.append(f"\n… and {more} more: type a letter or two to narrow", style="italic")
        self.completions.update(text)
        self.completions.add_class("-visible")

    @on(CommandLine.Changed)
    def hide_completions(self, event: CommandLine.Changed) -> None:
        self.completions.remove_class("-visible")
        if not event.value:
            self.hint.remove_class("-visible")

    @on(CommandLine.Hint)
    def show_hint(self, event: CommandLine.Hint) -> None:
        """The argument hint, on its own line while a history suggestion holds the grey text."""
        if event.value != self.command_line.value:
            return  # made for a line already changed
        if event.text:
            self.mount_hidden_panes()
            self.hint.update(Text.assemble(("needs: ", "dim"), (event.text, "italic")))
            self.hint.add_class("-visible")
        else:
            self.hint.remove_class("-visible")

    def show(self, feedback: Feedback) -> None:
        from ..commands.outcome import Outcome
        from ..present.render import error_text, notice_text, outcome_text

        results = self.results
        if isinstance(feedback, Outcome):
            if feedback.ok:
                results.write(outcome_text(feedback))
            else:
                results.write(notice_text(error_text(feedback), error=True))
        elif isinstance(feedback, Message):
            results.write(notice_text(feedback.text, error=feedback.level == "error"))
        elif feedback is UiStep.CLEAR:
            self.action_clear_log()
        elif feedback is UiStep.QUIT:
            self.exit(0)
        elif feedback in (UiStep.FRAMES_ON, UiStep.FRAMES_OFF):
            on = feedback is UiStep.FRAMES_ON
            self.frame_log.show_polls = on
            self.show(Message("poll frames shown" if on else "poll frames hidden"))

    @on(Worker.StateChanged)
    def worker_failed(self, event: Worker.StateChanged) -> None:
        """A bug must not end the session at the cell: say so and carry on."""
        if event.state == WorkerState.ERROR and self.is_running:
            self.show(Message(f"internal error: {event.worker.error!r}", "error"))

    # -------------------------------------------------------------- actions

    def action_toggle_polling(self, _shown: str = "") -> None:
        from ..commands.language import Simple, Step

        paused = not (self.status is not None and self.status.paused)
        for name in self.cell.names:  # in a cell: every target's polls
            self.cell.submit_command(Simple(Step.PAUSE if paused else Step.RESUME), None, name)

    def action_toggle_poll_frames(self) -> None:
        log = self.frame_log
        log.show_polls = not log.show_polls
        self.show(
            Message(
                "poll frames shown"
                if log.show_polls
                else "poll frames hidden (typed commands only; F3 shows them)"
            )
        )

    def action_toggle_scroll(self, _shown: str = "") -> None:
        log = self.frame_log
        log.auto_scroll = not log.auto_scroll
        self.sync_bindings()  # F4 says what it will do now
        log.update_title()
        if log.auto_scroll:
            log.scroll_end(animate=False)

    @on(IoPanel.Toggle)
    def toggle_from_grid(self, event: IoPanel.Toggle) -> None:
        """Space in the I/O grid: the table's toggle, with the same in-flight guard."""
        toggle(self, event.row, self.cell.current if self.cell_mode else "")

    def action_toggle_io_grid(self) -> None:
        """IO rows move from the table to the grid, or back."""
        shown = not self.io_panel.display
        self.io_panel.show(shown)
        self.table.set_hide_io(shown)
        self.refresh_table()
        self.kept.changed()

    @on(FrameLog.OptionsChanged)
    def log_options_changed(self) -> None:
        self.kept.changed()

    def _close_question(self, seq: int) -> None:
        """A write that ended (a cancel came before its answer) asks nothing any more."""
        from .confirm_screen import ConfirmWriteScreen

        screen = self.screen
        if isinstance(screen, ConfirmWriteScreen) and screen.question.seq == seq:
            screen.dismiss(False)

    def confirm_write(self, question: ConfirmWrite, target: str | None = None) -> None:
        """A write on a ``confirm`` target asks first: old → new, ``[y/N]``, default No;
        the engine polls on until the answer, then the focus is back where it was (a
        table row or a grid bit: the next Space toggles the next one)."""
        from .confirm_screen import ConfirmWriteScreen

        state = self.state_of(target)
        colour = state.status.colour if state.status is not None else state.colour
        held = question.seq == self._held_seq
        if held:  # what was typed after the write's Enter was typed ahead of this
            self.command_line.post_message(CommandLine.Asked())

        def answered(yes: bool | None) -> None:
            self.cell.answer_confirm(question.seq, bool(yes))
            if not yes:  # no write: the row's next Space need not wait for the refusal
                state.toggles.declined(question.seq)
            if held and self._held_seq == question.seq:
                self.command_line.post_message(CommandLine.Answered())

        named = target if self.cell_mode else None
        self.push_screen(ConfirmWriteScreen(question, colour, named), answered)

    def show_target(self, status: Status) -> None:
        """A profile's colour around the whole console and its label in the border's
        title, so two consoles on two robots can't be mixed up; none without a profile
        (the simulator, a plain host). A colour nobody knows keeps the default one."""
        screen = self.screen_stack[0]
        label = target_label(status)
        screen.set_class(label is not None, "-profile")
        colour = None
        if label is not None:
            from .confirm_screen import border_colour

            colour = border_colour(status.colour)
        if colour is not None:
            screen.styles.border = ("heavy", colour)
        else:
            screen.styles.border = None  # the stylesheet's, for -profile or not
        screen.border_title = Text(f" {label} ") if label is not None else None

    def action_clear_log(self) -> None:
        self.frame_log.clear()


def _shown_target(status: Status) -> tuple[str | None, str | None, str | None]:
    """What the border shows of a target: its profile, label and colour."""
    return status.profile, status.label, status.colour


def run_console(
    cell: Cell | Engine,
    history: History,
    watch_file: str | None,
    profile_names: Sequence[str] = (),
    after_first_paint: Callable[[], object] | None = None,
) -> int:
    """The console on a cell (one target: the console as it always was; an engine is
    taken as a cell of one); ``profile_names`` are the config file's targets (the
    palette's ``connect NAME`` entries); ``after_first_paint`` is called once its first
    screen is painted. Its settings are read here, before the app runs its loop."""
    from ..engine.config import config_path
    from ..engine.settings import SettingsFile

    app = RacConsoleApp(
        cell, history, watch_file, profile_names, settings=SettingsFile(config_path())
    )
    app.kept.load(app.available_themes)
    app.after_first_paint = after_first_paint
    if ascii_wanted():  # RAC_CONSOLE_ASCII=1, or Windows' old console host
        app.driver_class = ascii_driver(app.driver_class)
    keep_full_collections_rare()  # the start-up's objects frozen: no key waits on a full pass
    try:
        status = app.run() or 0
    finally:
        if app.terminal_watch is not None:
            app.terminal_watch.stop()
    return app.exit_status(status)
