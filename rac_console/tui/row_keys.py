"""What the console does with the keys on a row: a put made on the command line, the
trend view and the detail in the frame log's place, and what goes with unwatched rows.

The trend and the detail are opened from the table and leave it the focus, so the row
keys go on working (``↓ t`` the next row's trend, ``T`` an overlay, ``d``); Esc on the
table closes the one open, and Esc again goes to the command line.

Functions over the panes they touch, called by the console screen's handlers. A line
put on the command line is never sent without the user's own Enter; what reaches the
controller goes through the screen's ``submit_line``, the path of a typed line.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..protocol.text import terminal_safe
from .filter_line import FilterLine, focus_now

if TYPE_CHECKING:
    from textual.widget import Widget

    from ..commands.language import VarRef
    from ..engine.published.events import RowView
    from .members import MemberState
    from .panes import Panes


def addressed(cell_mode: bool, target: str, line: str) -> str:
    """A line made for a row, as shown: in a cell, after its target (``@robotB put …``)."""
    return f"@{target} {line}" if cell_mode and target else line


def type_ahead(panes: Panes, focused: Widget | None, character: str) -> None:
    """A character the table has no use for: the start of a command typed with the
    table focused. It goes to the command line, and so do the keys after it; keys
    queued behind a ``/`` go to the filter line it opened."""
    if isinstance(focused, FilterLine):
        focused.insert_text_at_cursor(character)
        return
    focus_now(panes.command_line)
    panes.command_line.type_ahead(character)  # held while a write may still ask


def put_on_command_line(panes: Panes, text: str) -> None:
    """A line for the user to finish and run with their own Enter."""
    command_line = panes.command_line
    command_line.value = text
    command_line.cursor_position = len(text)
    focus_now(command_line)


def put_on_line(panes: Panes, row: RowView, cell_mode: bool, target: str = "") -> str | None:
    """``p`` on a row: a ``put`` of its value on the command line, to edit and enter;
    what is wrong with the value as written, if anything."""
    from ..present.row_actions import put_line

    line = put_line(row.var, row.variant)
    put_on_command_line(panes, addressed(cell_mode, target, line.text))
    return line.problem or None


def close_detail(panes: Panes) -> None:
    """The frame log again, in the detail's place."""
    panes.row_detail.remove_class("-open")
    panes.frame_log.remove_class("-under-detail")
    views_changed(panes)


def close_views(panes: Panes) -> None:
    """Esc on the table: the detail or the trend closes, the table keeps the focus."""
    if panes.row_detail.is_open:
        close_detail(panes)
    if panes.trend_view.has_class("-open"):
        close_trend(panes)


def views_changed(panes: Panes) -> None:
    """The footer says what Esc does now (closes a view, or leaves the table)."""
    panes.table.refresh_bindings()


def open_detail(panes: Panes) -> None:
    """The row under the cursor in full, in the frame log's place (the log keeps
    collecting); it closes the trend view, which has the same place."""
    if panes.trend_view.has_class("-open"):
        close_trend(panes)
    panes.row_detail.add_class("-open")
    panes.frame_log.add_class("-under-detail")
    panes.detail_follows_cursor()
    views_changed(panes)


def open_trend(panes: Panes, row: RowView, target: str = "") -> None:
    """``t`` on a row: its trend in the frame log's place (again: closed); the table
    keeps the focus, for the next row's ``t``, ``T`` or ``d`` (F6 reaches the view)."""
    view = panes.trend_view
    if view.has_class("-open") and view.var == row.var and view.target == target:
        close_trend(panes)
        return
    if panes.row_detail.is_open:
        close_detail(panes)  # the same place: one at a time
    field = panes.table.field_of((target, row.var))
    view.show_row(row.var, terminal_safe(row.label), field, target)
    view.add_class("-open")
    panes.frame_log.add_class("-under-trend")
    views_changed(panes)


def overlay_trend(panes: Panes, row: RowView, target: str) -> str | None:
    """``T`` on a row (a cell): the row joins the open trend, on the same time axis
    (robotA's IO128 over robotB's IO64: the handshake); no trend open: ``t``'s. What
    to say when it is in the trend already."""
    view = panes.trend_view
    if not view.has_class("-open"):
        open_trend(panes, row, target)
        return None
    field = panes.table.field_of((target, row.var))
    if not view.add_row(row.var, terminal_safe(row.label), field, target):
        return f"{target} {row.var} is in the trend already"
    return None


def close_trend(panes: Panes) -> None:
    """Back to the frame log; focus goes back to the table only from the view."""
    had_focus = panes.trend_view.has_focus
    panes.trend_view.remove_class("-open")
    panes.frame_log.remove_class("-under-trend")
    if had_focus:
        focus_now(panes.table)
    views_changed(panes)


def cycle_trend_field(panes: Panes, target: str, var: VarRef) -> None:
    """``f`` in the trend view: the row's next field, in the table and the view."""
    panes.table.cycle_field((target, var))
    view = panes.trend_view
    view.field = panes.table.field_of((target, var))
    view.redraw()


def forget_rows(panes: Panes, state: MemberState, removed: set[VarRef]) -> None:
    """Unwatched rows: their trends and toggles go, and they leave the trend view
    (closed when nothing is left in it)."""
    view = panes.trend_view
    for var in removed:
        state.trends.forget(var)
        state.toggles.forget(var)
        shown = view.has_class("-open") and view.shows(state.name, var)
        if shown and view.forget(state.name, var):
            close_trend(panes)
