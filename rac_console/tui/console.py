"""The console screen: status line, watch table, frame log, results, command line.

It lays the panes out (:mod:`.panes`), runs the lines typed and the keys bound to it
(:mod:`.keys`), and reads what the engines publish (:class:`BatchReader`, paced by
:mod:`.pacing`); what a row's keys do is in :mod:`.row_keys`. The app around it owns
the lifecycle, the settings and the engine's wake-up.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import BindingType
from textual.message import Message as TextualMessage
from textual.reactive import reactive
from textual.screen import Screen
from textual.widget import Widget
from textual.widgets import DataTable, Input

from ..engine.published.feedback import Message
from ..engine.setup.where import Where
from ..present.cell_view import cell_targets
from ..present.status import connect_targets, writes_refused
from ..present.trends import has_trend
from . import keys, row_keys
from .command_line import CommandLine, dropped_text
from .feed import ConsoleFeed
from .filter_line import FilterLine, focus_now
from .footer import FittingFooter
from .io_panel import IoPanel
from .lines import Lines
from .members import Members
from .pacing import Pacing
from .panes import Panes
from .trend_view import TrendView
from .watch_table import WatchTable

if TYPE_CHECKING:
    from ..commands.language import Command
    from ..engine.cell.cell import Cell
    from ..engine.published.events import ConfirmWrite, RowView
    from ..engine.published.status import Status
    from ..present.history import History
    from .file_writes import FileWrites


class SettingChanged(TextualMessage):
    """A setting that stays (the I/O grid, a log toggle) changed: the app saves it."""


class ConsoleScreen(Screen[None]):
    """The console's one screen; modal screens (help, a write's question) go over it."""

    BINDINGS: ClassVar[list[BindingType]] = keys.CONSOLE
    #: The command line has the focus from the first paint: a key typed as soon as the
    #: screen shows acts there (Up recalls, Enter submits).
    AUTO_FOCUS = "#command"

    # What the footer's keys depend on (check_action), set in one place: sync_bindings.
    line_running = reactive(False, bindings=True)  # Esc cancels it
    polling_paused = reactive(False, bindings=True)  # F2 resumes
    log_frozen = reactive(False, bindings=True)  # F4 follows

    def __init__(
        self, cell: Cell, history: History, files: FileWrites, profile_names: Sequence[str] = ()
    ) -> None:
        super().__init__()
        self.cell = cell
        self.profile_names = tuple(profile_names)  # the palette offers connect NAME
        self.members = Members(cell)
        self.cell_mode = self.members.cell_mode
        self.history = history
        self.files = files  # history lines, written off this loop
        self.panes = panes = Panes.make(
            self.members, history, self._used, self.type_on_command_line, self.toggle_row
        )
        self.lines = Lines(cell, self.members, panes.command_line, self._line_started)
        #: Read before the engine starts: the palette's words for each profile.
        # Served to a browser, the config file's profiles are not shown (nor run).
        served = cell.where is Where.SERVED
        self.profiles = {} if served else dict(self.members.engine.profiles)
        panes.command_line.targets = tuple(connect_targets(self.profiles))
        panes.command_line.cell = tuple(cell_targets(cell))  # none for one target
        panes.command_line.enter = self.enter_line
        self.pacing = Pacing(self, self.update_all, self._clock_shown, self.refresh_table)
        self.feed = ConsoleFeed(
            self.members,
            panes,
            self.lines,
            history,
            files,
            ask=self.confirm_write,
            close_question=self._close_question,
            mark_target=self.show_target,
            subtitle=self._subtitled,
            refresh=self.refresh_table,
            quit=lambda: self.app.exit(0),
        )
        self.show = self.feed.show

    @property
    def status(self) -> Status | None:
        """The current target's status (in a cell of one: the status)."""
        return self.members.status

    def first_panes(self) -> ComposeResult:
        """What the first screen shows (mounted by the app: see its ``compose``); the
        hidden panes join it after its first paint."""
        yield from self.panes.shown_at_start(self.cell_mode)
        yield FittingFooter()

    def mount_hidden_panes(self) -> None:
        self.panes.mount_hidden(self)

    def _subtitled(self, subtitle: str) -> None:
        self.app.sub_title = subtitle

    def _used(self) -> frozenset[tuple[str, int]]:
        """Indices used or watched (the engine counts watched ones as used)."""
        return self.status.seen if self.status is not None else frozenset()

    # -------------------------------------------------------- what the engines said

    def drain_outbox(self) -> None:
        """Take everything the engines published since the last time, in order: the
        cell's own results, then each target's batch."""
        for name, batch in self.cell.drain():
            self.feed.read(name, batch)
        if self.cell_mode:
            self.panes.prompt.update(self.members.prompt_text())
        self.sync_bindings()

    # ----------------------------------------------------------- the screen, updated

    def update_all(self, log: bool, table: bool) -> None:
        """What the pacing decided is due: the outbox drained, then the log written and
        the table refreshed, each only with its turn."""
        self.drain_outbox()
        if log:
            self.flush_log()
            if table:
                self.refresh_table()

    def flush_log(self) -> None:
        self.pacing.flushed(self.panes.frame_log.flush())

    def frames_per_second(self) -> float:
        return self.pacing.frames_per_second()

    def _clock_shown(self) -> bool:
        """Whether anything on screen changes with time alone."""
        return bool(
            self.members.members_timed()  # rows' ages, a reply waited for, a retry
            or self.lines.pending  # the running line's time
            or self.frames_per_second() > 0  # the rate, back to 0
            or self.panes.status_bar.saying  # the watchdog's notice, until it goes
        )

    def caught_up(self, seconds: float) -> None:
        """The watchdog found the screen ``seconds`` behind what the engines published:
        everything is shown now, and the status line and the log say so."""
        from ..engine.published.events import Alert
        from ..present.status import NOTICE_SECONDS, caught_up_alert, caught_up_notice

        self.panes.status_bar.say(caught_up_notice(seconds), NOTICE_SECONDS)
        self.pacing.catch_up()  # the log's line after what was caught up: the newest
        self.panes.frame_log.add(Alert(caught_up_alert(seconds), local_failure=False))
        self.flush_log()
        self.pacing.clock_needed()

    def engine_stopped(self, name: str) -> None:
        """The watchdog found ``name``'s engine dead: said once, in red; its status line
        says so from now on (see the watchdog)."""
        from ..present.status import engine_stopped_text

        engine = self.members.states[name].member.engine
        self.show(Message(engine_stopped_text(self._named(name), engine.died), "error"))
        for seq in list(self.lines.pending):  # the engine answers them (not run); should
            self.lines.answered(seq)  # it not, nothing holds the keys or waits on them
        self.sync_bindings()
        self.refresh_table()

    def sync_bindings(self) -> None:
        """The one place the state the footer's keys depend on is set: a change shows
        the keys again (reactive ``bindings=True``)."""
        status = self.status
        self.line_running = bool(self.lines.pending)
        self.polling_paused = status is not None and status.paused
        self.log_frozen = not self.panes.frame_log.auto_scroll
        self.panes.table.refuses_writes = writes_refused(status)

    def refresh_table(self) -> None:
        """The table, the grid, the trend, the detail and the status line, up to date."""
        self.pacing.table_refreshed()
        self.panes.refresh(self.members, self.lines.running(), self.frames_per_second())

    def type_on_command_line(self, character: str) -> None:
        row_keys.type_ahead(self.panes, self.focused, character)

    def _line_started(self) -> None:
        self.sync_bindings()
        self.pacing.clock_needed()  # the running line's time

    def submit_line(
        self, line: str, command: Command | None = None, target: str | None = None
    ) -> int:
        """A line run as if typed (echoed, queued, cancelled by Esc), or ``command``
        shown as ``line`` on ``target`` (None: the current one): its sequence."""
        return self.lines.submit(line, command, target)

    def toggle_row(self, row: RowView | None, target: str = "") -> None:
        """Space on the table or the grid: write the opposite of the value shown, as
        ``put IO N off`` typed would (made here, shown as that line, never parsed back).
        While the row has not shown the last toggle's effect, another is refused."""
        from ..present.row_actions import toggle_command, toggle_refusal

        if row is None:
            self.show(Message("the table has no rows: watch TYPE INDEX adds one"))
            return
        state = self.members.state_of(target or None)
        toggled = toggle_command(row.var, row.variant)
        paused = state.status is not None and state.status.paused
        refusal = toggle_refusal(row.var, toggled, state.toggles.busy(row.var), paused)
        if refusal is not None or toggled is None:  # no toggle: the refusal says why
            self.show(Message(refusal or "nothing to toggle"))
            return
        command, line = toggled
        line = row_keys.addressed(self.cell_mode, target, line)
        # The keys typed after this Space must not answer its question, if it asks.
        seq = self.lines.toggle(line, command, target or None)
        state.toggles.start(row.var, seq, not bool(row.variant and row.variant.value))

    def _close_question(self, seq: int) -> None:
        from .confirm_screen import close_question

        close_question(self.app, seq)

    def confirm_write(self, question: ConfirmWrite, target: str | None = None) -> None:
        """A write on a ``confirm`` target asks first (see :func:`ask`)."""
        from .confirm_screen import ask

        ask(self.app, question, self.members.state_of(target), self._named(target), self.lines)

    def show_target(self, status: Status) -> None:
        from .borders import mark_target

        mark_target(self, status)

    def _named(self, target: str | None) -> str | None:
        return target if self.cell_mode else None

    # ---------------------------------------------------------- the command line

    def enter_line(self, line: str, may_hold: bool) -> bool:
        """The command line's Enter (or a pasted line): handed to the cell at once, in
        the order typed (lines run one at a time, each once, in order); True when the
        keys typed after it are held (see :meth:`Lines.enter`)."""
        self.panes.completions.hide()
        return self.lines.enter(line, may_hold)

    @on(CommandLine.Dropped)
    def keys_dropped(self, event: CommandLine.Dropped) -> None:
        if not self.lines.dropped(event.count):  # else said after the line's answer
            self.show(Message(dropped_text(event.count)))

    @on(CommandLine.TooLong)
    def line_too_long(self) -> None:
        from ..present.render import too_long_text

        if count := self.panes.command_line.refused():
            self.show(Message(too_long_text(count), "error"))

    @on(CommandLine.Completions)
    def list_completions(self, event: CommandLine.Completions) -> None:
        self.mount_hidden_panes()
        self.panes.completions.show(event.candidates)  # again: the next page

    @on(CommandLine.Changed)
    def hide_completions(self, event: CommandLine.Changed) -> None:
        self.panes.completions.hide()
        if not event.value:
            self.panes.hint.remove_class("-visible")

    @on(CommandLine.Hint)
    def show_hint(self, event: CommandLine.Hint) -> None:
        """The argument hint, on its own line while a history suggestion holds the grey
        text (none for a line already changed)."""
        hint = self.panes.hint
        if event.value == self.panes.command_line.value and event.text:
            self.mount_hidden_panes()
            hint.update(Text.assemble(("needs: ", "dim"), (event.text, "italic")))
            hint.add_class("-visible")
        elif event.value == self.panes.command_line.value:
            hint.remove_class("-visible")

    @on(CommandLine.HelpRequested)
    def help_requested(self) -> None:
        self.action_help()

    # ------------------------------------------------------------- row keys

    @on(WatchTable.RowAction)
    def row_action(self, event: WatchTable.RowAction) -> None:
        row, target, panes = event.row, event.target, self.panes
        if event.action == "filter":
            self.mount_hidden_panes()
            panes.table_filter.value = panes.table.filter_text
            panes.table_filter.open()
        elif row is None:
            self.show(Message("the table has no rows: watch TYPE INDEX adds one"))
        elif event.action == "put":
            problem = row_keys.put_on_line(panes, row, self.cell_mode, target)
            if problem:
                self.show(Message(problem, "error"))
        elif event.action == "toggle":
            self.toggle_row(row, target)
        elif event.action == "unwatch":
            from ..commands.language import Unwatch

            line = f"unwatch {row.var.kind.code} {row.var.index}"
            shown = row_keys.addressed(self.cell_mode, target, line)
            self.submit_line(shown, Unwatch((row.var,)), target or None)
        elif event.action in ("trend", "overlay") and not has_trend(row.var.kind):
            self.show(Message(f"{row.var} has no trend: t draws numbers, IO bits and positions"))
        elif event.action == "trend":
            self.mount_hidden_panes()
            row_keys.open_trend(panes, row, target)
        elif event.action == "overlay":
            self.mount_hidden_panes()
            said = row_keys.overlay_trend(panes, row, target)
            if said:
                self.show(Message(said))

    @on(DataTable.RowHighlighted)
    def cursor_moved(self, event: DataTable.RowHighlighted) -> None:
        """The cursor moved: the detail shows its row at once, not at the next refresh."""
        if event.data_table is self.panes.table:
            self.panes.detail_follows_cursor()

    @on(TrendView.Closed)
    def trend_closed(self) -> None:
        row_keys.close_trend(self.panes)

    @on(TrendView.FieldCycled)
    def trend_field_cycled(self, event: TrendView.FieldCycled) -> None:
        row_keys.cycle_trend_field(self.panes, event.target, event.var)

    @on(IoPanel.Toggle)
    def toggle_from_grid(self, event: IoPanel.Toggle) -> None:
        """Space in the I/O grid: the table's toggle, with the same in-flight guard."""
        self.toggle_row(event.row, self.cell.current if self.cell_mode else "")

    # ------------------------------------------------------------------- keys

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Esc cancels only while a typed line is running (elsewhere it leaves a pane);
        F2 and F4 show the one of their pair that says what they will do."""
        if action == "cancel_command":
            return self.line_running
        if action == "next_target":
            return self.cell_mode
        if action == "close_view":  # Esc on the table: else it leaves the table
            return self.panes.view_open
        if action == "toggle_polling":
            return self.polling_paused == (parameters == ("resume",))
        if action == "toggle_scroll":
            return self.log_frozen == (parameters == ("follow",))
        return True

    def action_next_target(self) -> None:
        """F8: ``use`` the next target of the cell, as typed."""
        from ..commands.language import Use

        names = self.cell.names
        following = names[(names.index(self.cell.current) + 1) % len(names)]
        self.submit_line(f"use {following}", Use(following))

    def action_cancel_command(self) -> None:
        """Esc: the running line ends (a wait, a latency run, a request in flight), and
        the lines typed behind it are not run."""
        self.lines.cancel()

    def action_interrupt(self) -> None:
        """Ctrl+C: cancel as Esc does. With nothing running, text selected in the
        command line (or on screen) is copied, as Textual does; else it says how to
        quit, for the hand that reached for Ctrl+C to leave."""
        if self.lines.cancel():
            return
        focused = self.app.focused
        if isinstance(focused, Input) and focused.selected_text:
            focused.action_copy()
        elif selected := self.app.screen.get_selected_text():
            self.app.copy_to_clipboard(selected)
        else:
            quit_key = keys.key_for("app.quit") or "Ctrl+Q"
            text = f"Nothing is running to cancel. {quit_key} quits."
            self.notify(text, title="Ctrl+C", markup=False)

    def action_focus_pane(self, step: int) -> None:
        """F6 / Shift+F6: command line → table (→ I/O grid) → frame log or trend → back."""
        shown = self.panes.in_focus_order()
        focused: Widget | None = self.focused
        if isinstance(focused, FilterLine) and isinstance(focused.target, Widget):
            focused = focused.target  # a pane's filter line counts as its pane
        index = shown.index(focused) if focused in shown else 0
        focus_now(shown[(index + step) % len(shown)])

    def action_focus_command_line(self) -> None:
        focus_now(self.panes.command_line)

    def action_close_view(self) -> None:
        row_keys.close_views(self.panes)

    def action_toggle_polling(self, _shown: str = "") -> None:
        from ..commands.language import Simple, Step

        paused = not (self.status is not None and self.status.paused)
        for name in self.cell.names:  # in a cell: every target's polls
            self.cell.submit_command(Simple(Step.PAUSE if paused else Step.RESUME), None, name)

    def action_toggle_poll_frames(self) -> None:
        self.show(Message(self.panes.frame_log.toggle_polls()))

    def action_toggle_hex(self) -> None:
        self.show(Message(self.panes.frame_log.toggle_hex()))

    def action_toggle_frame_times(self) -> None:
        self.show(Message(self.panes.frame_log.toggle_gaps()))

    def action_filter_frames(self) -> None:
        """``/`` in the frame log: its filter line, with the filter as it is."""
        self.mount_hidden_panes()
        self.panes.log_filter.open()

    def action_toggle_scroll(self, _shown: str = "") -> None:
        log = self.panes.frame_log
        log.auto_scroll = not log.auto_scroll
        self.sync_bindings()  # F4 says what it will do now
        log.update_title()
        if log.auto_scroll:
            log.scroll_end(animate=False)

    def action_toggle_io_grid(self) -> None:
        """IO rows move from the table to the grid, or back."""
        shown = not self.panes.io_panel.display
        self.panes.io_panel.show(shown)
        self.panes.table.set_hide_io(shown)
        self.refresh_table()
        self.post_message(SettingChanged())

    def action_clear_log(self) -> None:
        self.panes.frame_log.clear()

    def action_toggle_detail(self) -> None:
        """``d`` on the table (or the palette): the row under the cursor in full, in the
        frame log's place, following the cursor; again: the log is back."""
        if self.panes.row_detail.is_open:
            row_keys.close_detail(self.panes)
        else:
            self.mount_hidden_panes()
            row_keys.open_detail(self.panes)

    def action_help(self) -> None:
        """F1, ``?`` on an empty line, the palette: open the help (F1 again closes it)."""
        from ..present.help_text import help_sections
        from .help_screen import HelpScreen, console_key_groups

        if isinstance(self.app.screen, HelpScreen):
            self.app.screen.dismiss(None)
            return
        sections = help_sections(console_key_groups(type(self.app), self.cell_mode))
        command_line = self.panes.command_line
        # Back on the command line, wherever the help was opened from.
        self.app.push_screen(HelpScreen(sections), lambda _: focus_now(command_line))
