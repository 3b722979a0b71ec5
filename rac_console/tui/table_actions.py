"""What the console does with keys on the watch table, its filter and the trend view.

A mixin of :class:`~rac_console.tui.app.RacConsoleApp`, kept apart so the app stays a
composition. Everything that reaches the controller goes through ``engine.submit``,
the path of a typed line (read-only refusal, frame log, record, result echo); a line
put on the command line is never sent without the user's own Enter.
"""

from __future__ import annotations

import time

from textual.widget import Widget
from textual.widgets import DataTable

from ..commands.language import VarRef
from ..engine import Cycle, Engine, Feedback, Message, Result, RowView, Status
from ..present.row_actions import PendingToggles, put_line, toggle_line
from ..present.trends import TrendStore, has_trend
from ..protocol.text import terminal_safe
from .command_line import CommandLine
from .filter_line import FilterLine, focus_now
from .frame_log import FrameLog
from .io_panel import IoPanel
from .row_detail import RowDetail
from .trend_view import TrendView
from .watch_table import WatchTable, writes_refused


class TableFilter(FilterLine):
    """The watch table's filter line, shown by ``/``: rows by name or label."""

    def __init__(self, table: WatchTable, **kwargs: object) -> None:
        super().__init__(table, "filter rows: name or label", **kwargs)
        table.filter_line = self  # ``/`` on the table opens this line at once


#: The command line's placeholder: examples that work on the target.
PLACEHOLDER = "get P 1 · put IO 20 on · watch IO 0-7 · help"
READ_ONLY_PLACEHOLDER = "get P 1 · watch IO 0-7 · help"


class TableActions:
    """Pane focus, row keys, IO toggles, the trend store and view."""

    engine: Engine
    status: Status | None
    command_line: CommandLine
    table: WatchTable
    frame_log: FrameLog
    table_filter: TableFilter
    io_panel: IoPanel  # the I/O bit grid (F5), a pane while shown
    trend_view: TrendView
    row_detail: RowDetail  # the row under the cursor in full (d), in the log's place
    trends: TrendStore
    toggles: PendingToggles

    def show(self, feedback: Feedback) -> None:
        raise NotImplementedError  # the app's

    def follow_status(self, old: Status | None, new: Status) -> None:
        """A new status: the footer's keys (F2's word, Space on a read-only target)
        and the command line's examples follow it."""
        if old is None or (old.paused, writes_refused(old)) != (
            new.paused,
            writes_refused(new),
        ):
            self.refresh_bindings()  # type: ignore[attr-defined]  # the App's
        self.command_line.placeholder = (
            READ_ONLY_PLACEHOLDER if writes_refused(new) else PLACEHOLDER
        )

    # --------------------------------------------------------------- focus

    def _panes(self) -> list[Widget]:
        panes: list[Widget] = [self.command_line, self.table]
        if self.io_panel.display:
            panes.append(self.io_panel)
        if self.trend_view.has_class("-open"):
            panes.append(self.trend_view)
        elif not self.row_detail.is_open:  # the detail takes no focus: the arrows stay
            panes.append(self.frame_log)  # the table's
        return panes

    def action_focus_pane(self, step: int) -> None:
        """F6 / Shift+F6: command line → table (→ I/O grid) → frame log or trend → back."""
        panes = self._panes()
        focused = self.focused  # type: ignore[attr-defined]
        if isinstance(focused, FilterLine) and isinstance(focused.target, Widget):
            focused = focused.target  # a pane's filter line counts as its pane
        index = panes.index(focused) if focused in panes else 0
        focus_now(panes[(index + step) % len(panes)])

    def action_focus_command_line(self) -> None:
        focus_now(self.command_line)

    def type_on_command_line(self, character: str) -> None:
        """A character the table has no use for: the start of a command typed with the
        table focused. It goes to the command line, and so do the keys after it; keys
        queued behind a ``/`` go to the filter line it opened."""
        focused = self.focused  # type: ignore[attr-defined]
        if isinstance(focused, FilterLine):
            focused.insert_text_at_cursor(character)
            return
        command_line = self.command_line
        focus_now(command_line)
        command_line.type_ahead(character)  # held while a write may still ask

    # ------------------------------------------------------------ row keys

    def on_watch_table_row_action(self, event: WatchTable.RowAction) -> None:
        row = event.row
        if event.action == "filter":
            self.table_filter.value = self.table.filter_text
            self.table_filter.open()
        elif row is None:
            self.show(Message("the table has no rows: watch TYPE INDEX adds one"))
        elif event.action == "put":
            self._put_on_line(row)
        elif event.action == "toggle":
            self._toggle(row)
        elif event.action == "unwatch":
            self.submit_line(f"unwatch {row.var.kind.code} {row.var.index}")
        elif event.action == "trend" and not has_trend(row.var.kind):
            self.show(Message(f"{row.var} has no trend: t draws numbers, IO bits and positions"))
        elif event.action == "trend":
            self._trend(row)

    def toggle_row(self, row: RowView | None) -> None:
        """Space on the table, handed over as it is read (the keys after it wait)."""
        if row is None:
            self.show(Message("the table has no rows: watch TYPE INDEX adds one"))
        else:
            self._toggle(row)

    def _put_on_line(self, row: RowView) -> None:
        line = put_line(row.var, row.variant)
        if line.problem:
            self.show(Message(line.problem, "error"))
        command_line = self.command_line
        command_line.value = line.text
        command_line.cursor_position = len(line.text)
        focus_now(command_line)

    def _toggle(self, row: RowView) -> None:
        """Space: write the opposite of the value shown, as a typed ``put IO N off``.

        While the row has not shown the effect of the last toggle, another Space is
        refused: it would toggle from a value already being replaced.
        """
        var = row.var
        line = toggle_line(var, row.variant)
        if line is None:
            why = "is not an IO row" if var.kind.code != "IO" else "has no value read yet"
            self.show(Message(f"Space toggles an IO bit: {var} {why}; nothing sent"))
            return
        if self.toggles.busy(var):
            paused = self.status is not None and self.status.paused
            wait = " (polling is paused: F2 resumes it)" if paused else ""
            self.show(Message(f"{var}: the last toggle has not come back yet{wait}; nothing sent"))
            return
        may_ask = self._may_ask(line)
        seq = self.submit_line(line)
        if may_ask:  # the keys typed after this Space must not answer its question
            self.command_line.hold()
            self._hold_keys(seq, queued=False)
        self.toggles.start(var, seq, not bool(row.variant and row.variant.value))

    # --------------------------------------------------------------- trends

    def take_cycle(self, cycle: Cycle) -> None:
        """A poll cycle from the outbox: its values go to the trends (not an earlier
        target's, drained after the change)."""
        if self.status is not None and cycle.target_id != self.status.target_id:
            return
        self.trends.add_cycle(cycle)
        if self.toggles.cycle(cycle):
            self.refresh_table()

    def take_result(self, result: Result) -> None:
        if self.toggles.result(result):
            self.refresh_table()

    def forget_rows(self, removed: set[VarRef]) -> None:
        """Unwatched rows: their trends and toggles go, and their trend view closes."""
        for var in removed:
            self.trends.forget(var)
            self.toggles.forget(var)
            if self.trend_view.var == var and self.trend_view.has_class("-open"):
                self._close_trend()

    def refresh_table(self) -> None:
        raise NotImplementedError  # the app's

    def submit_line(self, line: str) -> int:
        raise NotImplementedError  # the app's

    def _may_ask(self, line: str) -> bool:
        raise NotImplementedError  # the app's

    def _hold_keys(self, seq: int, queued: bool) -> None:
        raise NotImplementedError  # the app's

    # ------------------------------------------------------------ the detail

    def action_toggle_detail(self) -> None:
        """``d`` on the table (or the palette): the row under the cursor in full, in the
        frame log's place (the log keeps collecting), following the cursor; again: the
        log is back. It closes the trend view, which has the same place."""
        detail = self.row_detail
        if detail.is_open:
            self._close_detail()
            return
        if self.trend_view.has_class("-open"):
            self._close_trend()
        detail.add_class("-open")
        self.frame_log.add_class("-under-detail")
        self.show_detail()

    def _close_detail(self) -> None:
        self.row_detail.remove_class("-open")
        self.frame_log.remove_class("-under-detail")

    def show_detail(self) -> None:
        """The open detail follows the table's cursor and the polls."""
        if self.row_detail.is_open:
            self.row_detail.show_row(self.table.cursor_view(), time.monotonic())

    def on_data_table_row_highlighted(self, event: DataTable.RowHighlighted) -> None:
        """The cursor moved: the detail shows its row at once, not at the next refresh."""
        if event.data_table is self.table:
            self.show_detail()

    # --------------------------------------------------------------- trends

    def _trend(self, row: RowView) -> None:
        view = self.trend_view
        if view.has_class("-open") and view.var == row.var:
            self._close_trend()
            return
        if self.row_detail.is_open:
            self._close_detail()  # the same place: one at a time
        view.show_row(row.var, terminal_safe(row.label), self.table.field_of(row.var))
        view.add_class("-open")
        self.frame_log.add_class("-under-trend")
        view.focus()

    def _close_trend(self) -> None:
        """Back to the frame log; focus goes back to the table only from the view."""
        had_focus = self.trend_view.has_focus
        self.trend_view.remove_class("-open")
        self.frame_log.remove_class("-under-trend")
        if had_focus:
            focus_now(self.table)

    def on_trend_view_closed(self, event: TrendView.Closed) -> None:
        self._close_trend()

    def on_trend_view_field_cycled(self, event: TrendView.FieldCycled) -> None:
        self.table.cycle_field(event.var)
        view = self.trend_view
        view.field = self.table.field_of(event.var)
        view.redraw()

    def redraw_trend(self) -> None:
        """At the table's refresh rate: the open view follows its row's field choice."""
        view = self.trend_view
        if view.has_class("-open") and view.var is not None:
            view.field = self.table.field_of(view.var)
            view.redraw()
