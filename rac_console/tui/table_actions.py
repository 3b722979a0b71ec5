"""What the console does with keys on the watch table, its filter and the trend view.

A mixin of the app, kept apart so the app stays a composition; it needs of the app only
what :class:`~rac_console.tui.host.ConsoleHost` names. Its methods are the app's
handlers and actions; what they share are the functions below them, over the host.

Everything that reaches the controller goes through ``submit_line``, the path of a
typed line (read-only refusal, frame log, record, result echo); a line put on the
command line is never sent without the user's own Enter.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from textual.widget import Widget
from textual.widgets import DataTable

from ..engine.feedback import Message
from ..present.trends import has_trend
from ..protocol.text import terminal_safe
from .filter_line import FilterLine, focus_now
from .trend_view import TrendView
from .watch_table import WatchTable, writes_refused

if TYPE_CHECKING:
    from ..commands.language import VarRef
    from ..engine.events import Cycle, Result, RowView
    from ..engine.status import Status
    from .host import ConsoleHost

#: The command line's placeholder: examples that work on the target. A write is
#: suggested on the built-in simulator only: on a controller, the first thing a newcomer
#: reads is a read.
PLACEHOLDER = "get P 1 · put IO 20 on · watch IO 0-7 · help"
READ_ONLY_PLACEHOLDER = "get P 1 · watch IO 0-7 · help"


def placeholder_for(status: Status | None) -> str:
    """The examples for this target (the reads alone until its status is known)."""
    if status is None or writes_refused(status) or not status.is_simulator:
        return READ_ONLY_PLACEHOLDER
    return PLACEHOLDER


class TableActions:
    """Pane focus, row keys, IO toggles, the trend store and view."""

    def follow_status(self: ConsoleHost, old: Status | None, new: Status) -> None:
        """A new status: the command line's examples follow it (the footer's keys
        follow it by the app's ``sync_bindings``)."""
        self.command_line.placeholder = placeholder_for(new)

    # --------------------------------------------------------------- focus

    def action_focus_pane(self: ConsoleHost, step: int) -> None:
        """F6 / Shift+F6: command line → table (→ I/O grid) → frame log or trend → back."""
        shown = panes(self)
        focused = self.focused
        if isinstance(focused, FilterLine) and isinstance(focused.target, Widget):
            focused = focused.target  # a pane's filter line counts as its pane
        index = shown.index(focused) if focused in shown else 0
        focus_now(shown[(index + step) % len(shown)])

    def action_focus_command_line(self: ConsoleHost) -> None:
        focus_now(self.command_line)

    def type_on_command_line(self: ConsoleHost, character: str) -> None:
        """A character the table has no use for: the start of a command typed with the
        table focused. It goes to the command line, and so do the keys after it; keys
        queued behind a ``/`` go to the filter line it opened."""
        focused = self.focused
        if isinstance(focused, FilterLine):
            focused.insert_text_at_cursor(character)
            return
        command_line = self.command_line
        focus_now(command_line)
        command_line.type_ahead(character)  # held while a write may still ask

    # ------------------------------------------------------------ row keys

    def on_watch_table_row_action(self: ConsoleHost, event: WatchTable.RowAction) -> None:
        row = event.row
        if event.action == "filter":
            self.mount_hidden_panes()
            self.table_filter.value = self.table.filter_text
            self.table_filter.open()
        elif row is None:
            self.show(Message("the table has no rows: watch TYPE INDEX adds one"))
        elif event.action == "put":
            put_on_line(self, row, event.target)
        elif event.action == "toggle":
            toggle(self, row, event.target)
        elif event.action == "unwatch":
            from ..commands.language import Unwatch

            shown = addressed(self, event.target, f"unwatch {row.var.kind.code} {row.var.index}")
            self.submit_line(shown, Unwatch((row.var,)), event.target or None)
        elif event.action in ("trend", "overlay") and not has_trend(row.var.kind):
            self.show(Message(f"{row.var} has no trend: t draws numbers, IO bits and positions"))
        elif event.action == "trend":
            open_trend(self, row, event.target)
        elif event.action == "overlay":
            overlay_trend(self, row, event.target)

    def toggle_row(self: ConsoleHost, row: RowView | None, target: str = "") -> None:
        """Space on the table, handed over as it is read (the keys after it wait)."""
        if row is None:
            self.show(Message("the table has no rows: watch TYPE INDEX adds one"))
        else:
            toggle(self, row, target)

    # --------------------------------------------------------------- trends

    def take_cycle(self: ConsoleHost, cycle: Cycle, name: str | None = None) -> None:
        """A poll cycle of target ``name``: its values go to its trends (not an earlier
        target's, drained after the change)."""
        state = self.state_of(name)
        if state.status is not None and cycle.target_id != state.status.target_id:
            return
        state.trends.add_cycle(cycle)
        if state.toggles.cycle(cycle):
            self.refresh_table()

    def take_result(self: ConsoleHost, result: Result, name: str | None = None) -> None:
        if self.state_of(name).toggles.result(result):
            self.refresh_table()

    def forget_rows(self: ConsoleHost, removed: set[VarRef], name: str | None = None) -> None:
        """Unwatched rows: their trends and toggles go, and they leave the trend view
        (closed when nothing is left in it)."""
        state = self.state_of(name)
        view = self.trend_view
        for var in removed:
            state.trends.forget(var)
            state.toggles.forget(var)
            shown = view.has_class("-open") and view.shows(state.name, var)
            if shown and view.forget(state.name, var):
                close_trend(self)

    # ------------------------------------------------------------ the detail

    def action_toggle_detail(self: ConsoleHost) -> None:
        """``d`` on the table (or the palette): the row under the cursor in full, in the
        frame log's place (the log keeps collecting), following the cursor; again: the
        log is back. It closes the trend view, which has the same place."""
        detail = self.row_detail
        if detail.is_open:
            close_detail(self)
            return
        self.mount_hidden_panes()
        if self.trend_view.has_class("-open"):
            close_trend(self)
        detail.add_class("-open")
        self.frame_log.add_class("-under-detail")
        detail_follows_cursor(self)

    def show_detail(self: ConsoleHost) -> None:
        detail_follows_cursor(self)

    def on_data_table_row_highlighted(self: ConsoleHost, event: DataTable.RowHighlighted) -> None:
        """The cursor moved: the detail shows its row at once, not at the next refresh."""
        if event.data_table is self.table:
            detail_follows_cursor(self)

    # --------------------------------------------------------------- trends

    def on_trend_view_closed(self: ConsoleHost, event: TrendView.Closed) -> None:
        close_trend(self)

    def on_trend_view_field_cycled(self: ConsoleHost, event: TrendView.FieldCycled) -> None:
        self.table.cycle_field((event.target, event.var))
        view = self.trend_view
        view.field = self.table.field_of((event.target, event.var))
        view.redraw()

    def redraw_trend(self: ConsoleHost) -> None:
        """At the table's refresh rate: the open view follows its row's field choice."""
        view = self.trend_view
        if view.has_class("-open") and view.var is not None:
            view.fields = [self.table.field_of((t, v)) for t, v, _ in view.series]
            view.redraw()


def panes(host: ConsoleHost) -> list[Widget]:
    """The panes F6 goes through, in order: the ones shown."""
    shown: list[Widget] = [host.command_line, host.table]
    if host.io_panel.display:
        shown.append(host.io_panel)
    if host.trend_view.has_class("-open"):
        shown.append(host.trend_view)
    elif not host.row_detail.is_open:  # the detail takes no focus: the arrows stay
        shown.append(host.frame_log)  # the table's
    return shown


def addressed(host: ConsoleHost, target: str, line: str) -> str:
    """A line made for a row, as shown: in a cell, after its target (``@robotB put …``)."""
    return f"@{target} {line}" if host.cell_mode and target else line


def put_on_line(host: ConsoleHost, row: RowView, target: str = "") -> None:
    """``p`` on a row: a ``put`` of its value on the command line, to edit and enter."""
    from ..present.row_actions import put_line

    line = put_line(row.var, row.variant)
    if line.problem:
        host.show(Message(line.problem, "error"))
    command_line = host.command_line
    text = addressed(host, target, line.text)
    command_line.value = text
    command_line.cursor_position = len(text)
    focus_now(command_line)


def toggle(host: ConsoleHost, row: RowView, target: str = "") -> None:
    """Space: write the opposite of the value shown, as ``put IO N off`` typed would
    (the command made here, shown as that line, never parsed back).

    While the row has not shown the effect of the last toggle, another Space is
    refused: it would toggle from a value already being replaced.
    """
    from ..present.row_actions import toggle_command

    var = row.var
    toggled = toggle_command(var, row.variant)
    if toggled is None:
        why = "is not an IO row" if var.kind.code != "IO" else "has no value read yet"
        host.show(Message(f"Space toggles an IO bit: {var} {why}; nothing sent"))
        return
    state = host.state_of(target or None)
    toggles = state.toggles
    if toggles.busy(var):
        paused = state.status is not None and state.status.paused
        wait = " (polling is paused: F2 resumes it)" if paused else ""
        host.show(Message(f"{var}: the last toggle has not come back yet{wait}; nothing sent"))
        return
    command, line = toggled
    line = addressed(host, target, line)
    may_ask = host.may_ask(line)
    seq = host.submit_line(line, command, target or None)
    if may_ask:  # the keys typed after this Space must not answer its question
        host.command_line.hold()
        host.hold_keys(seq, queued=False)
    toggles.start(var, seq, not bool(row.variant and row.variant.value))


def close_detail(host: ConsoleHost) -> None:
    """The frame log again, in the detail's place."""
    host.row_detail.remove_class("-open")
    host.frame_log.remove_class("-under-detail")


def detail_follows_cursor(host: ConsoleHost) -> None:
    """The open detail follows the table's cursor and the polls."""
    if host.row_detail.is_open:
        host.row_detail.show_row(host.table.cursor_view(), time.monotonic())


def open_trend(host: ConsoleHost, row: RowView, target: str = "", focus: bool = True) -> None:
    """``t`` on a row: its trend in the frame log's place (again: closed); focused
    unless ``focus`` is False (``T``: the table keeps it, for the next row's ``T``)."""
    view = host.trend_view
    if view.has_class("-open") and view.var == row.var and view.target == target:
        close_trend(host)
        return
    host.mount_hidden_panes()
    if host.row_detail.is_open:
        close_detail(host)  # the same place: one at a time
    field = host.table.field_of((target, row.var))
    view.show_row(row.var, terminal_safe(row.label), field, target)
    view.add_class("-open")
    host.frame_log.add_class("-under-trend")
    if focus:
        view.focus()


def overlay_trend(host: ConsoleHost, row: RowView, target: str) -> None:
    """``T`` on a row (a cell): the row joins the open trend, on the same time axis
    (robotA's IO128 over robotB's IO64: the handshake); no trend open: ``t``'s."""
    view = host.trend_view
    if not view.has_class("-open"):
        open_trend(host, row, target, focus=False)  # the next row's T, from the table
        return
    field = host.table.field_of((target, row.var))
    if not view.add_row(row.var, terminal_safe(row.label), field, target):
        host.show(Message(f"{target} {row.var} is in the trend already"))


def close_trend(host: ConsoleHost) -> None:
    """Back to the frame log; focus goes back to the table only from the view."""
    had_focus = host.trend_view.has_focus
    host.trend_view.remove_class("-open")
    host.frame_log.remove_class("-under-trend")
    if had_focus:
        focus_now(host.table)
