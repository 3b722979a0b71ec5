"""The live watch table: keyed rows, updated in place, only the cells that changed.

Rows are keyed by variable name (``P10``), so the cursor follows its variable through
sorting, filtering and rows coming and going. Keys on a row do not act themselves:
they post :class:`WatchTable.RowAction` and the app decides (a key never writes to a
controller without going through the same path as a typed line). What a row's cells
show is :mod:`.row_cells`'; the refresh budget (rows in view now, the others in turn)
lives here, beside the rows it keeps up to date.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from itertools import islice
from typing import TYPE_CHECKING, ClassVar

from rich.text import Text
from textual import events
from textual.binding import BindingType
from textual.message import Message
from textual.reactive import reactive
from textual.widgets import DataTable

from ..present.filtering import needle_of
from ..present.table_rows import RowKey, SortMode, ordered_keys, table_key
from ..present.trends import field_labels
from . import keys
from .filter_line import FilterLine
from .row_cells import differs, row_cells, table_title, target_cell, trend_cell

if TYPE_CHECKING:
    from ..commands.language import VarRef
    from ..engine.published.events import RowView
    from ..present.trends import TrendStore

#: Status, age and trend before the value, so they stay in view when a long P or J
#: value is cut off on a narrow terminal.
COLUMNS = (
    ("var", "Variable"),
    ("label", "Label"),
    ("status", "Status"),
    ("changed", "Changed"),
    ("trend", "Trend"),
    ("value", "Value"),
    ("type", "VARTYPE"),
)
#: A cell's table has its target first.
TARGET_COLUMN = ("target", "Target")
#: The bottom border while values are cut: how to read a row whole.
CUT_HINT = "values cut: F6, then d shows a row in full"
CUT_FOCUSED = "values cut: d shows the row in full"
#: Measurings of the table to wait at most for new rows to count before they are
#: scrolled to (the rows added are measured once the table's queue runs dry, which
#: under load can be many screen refreshes later).
REVEAL_TRIES = 5


#: Rows out of view brought up to date per refresh (the rest wait their turn, or their
#: scroll into view): a constant cost per refresh, whatever the table holds.
OFF_VIEW_PER_REFRESH = 16
#: Rows either side of the view refreshed with it (a scroll of a line or two shows
#: them at once).
VIEW_MARGIN = 2


class WatchTable(DataTable[object]):
    """The app calls :meth:`refresh_rows` with every row it holds, as rows come and as
    the clock ticks."""

    #: The target refuses writes (set by the app as its status changes): no Space shown.
    refuses_writes = reactive(False, bindings=True)

    BINDINGS: ClassVar[list[BindingType]] = keys.WATCH_TABLE

    class RowAction(Message):
        """A key on a row (``put``, ``toggle``, ``unwatch``, ``trend``, ``overlay``), or
        ``filter``."""

        def __init__(self, action: str, row: RowView | None, target: str = "") -> None:
            super().__init__()
            self.action = action
            self.row = row  # as shown when the key was pressed; None on an empty table
            self.target = target  # the row's target (its cell member's name)

    #: The printable keys the table acts on; any other goes to the command line.
    ACTION_CHARACTERS = frozenset(" /sftd")

    def on_key(self, event: events.Key) -> None:
        """Typing a command with the table focused must not fire row keys one by one
        (`t` opens a trend, the space writes a bit): the first character no binding
        takes moves it, and everything after it, to the command line."""
        character = event.character
        # Keys already on their way when the first one left for the command line (or
        # for the filter line) follow it.
        elsewhere = self.screen.focused is not self  # (has_focus waits for the Blur event)
        if character == "/" and not elsewhere and self.filter_line is not None:
            # Opened here and now, not by the binding's message: the keys queued behind
            # the slash must find the filter line focused.
            event.stop()
            event.prevent_default()
            self.filter_line.open()
            return
        if character == " " and not elsewhere:
            # Here and now, not by the binding (which runs once the key has bubbled up
            # to the app, by then on the pane the keys after it moved the focus to): a
            # y typed after it must find the write started, and held if it may ask. On
            # a read-only target it is still answered: the engine says why.
            event.stop()
            event.prevent_default()
            self._on_toggle(self.cursor_view(), self.cursor_target())
            return
        if (
            event.is_printable
            and character
            and (elsewhere or character not in self.ACTION_CHARACTERS)
        ):
            event.stop()
            event.prevent_default()
            # At once, not by a message: the keys queued behind this one must find the
            # focus already moved.
            self._on_typed(character)

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """No Space in the footer on a read-only target (it still says why, see on_key);
        the overlay of trends only in a cell."""
        if action == "row" and parameters == ("overlay",):
            return bool(self.cell)
        return not (action == "row" and parameters == ("toggle",) and self.refuses_writes)

    def __init__(
        self,
        trends: Callable[[str], TrendStore],
        on_typed: Callable[[str], None],
        on_toggle: Callable[[RowView | None, str], None],
        cell: Sequence[tuple[str, str | None]] = (),
        **kwargs: object,
    ) -> None:
        """``trends(name)``: a target's trend store; ``on_typed(character)``: a key typed
        here that belongs on the command line; ``on_toggle(row, target)``: Space on a
        row, handed over at once (see :meth:`on_key`); ``cell``: a cell's targets (name,
        colour) when it has more than one: a Target column, rows grouped by target."""
        super().__init__(cursor_type="row", zebra_stripes=True, **kwargs)  # type: ignore[arg-type]
        self.trends = trends
        self._on_typed = on_typed
        self._on_toggle = on_toggle
        self.cell = tuple(cell)
        self._places = {name: n for n, (name, _) in enumerate(self.cell)}
        self._colours = dict(self.cell)
        self.columns_shown = (TARGET_COLUMN, *COLUMNS) if self.cell else COLUMNS
        if self.cell:  # T overlays a trend: a key of the table's, not a command's start
            self.ACTION_CHARACTERS = self.ACTION_CHARACTERS | {"T"}
        self._owner: dict[str, RowKey] = {}  # every row's key: its target and variable
        self._target_plain: dict[str, str] = {}  # a cell's rows: their Target cell's text
        #: The filter line ``/`` opens (it sets itself here).
        self.filter_line: FilterLine | None = None
        #: The field each V P J T row's trend follows (index into its labels); `f` cycles it.
        self.fields: dict[RowKey, int] = {}
        self._shown: dict[str, tuple[object, ...]] = {}
        self._views: dict[str, RowView] = {}  # every row held, as last refreshed
        self._order: list[str] = []  # the keys as the DataTable holds them
        self._added: dict[str, int] = {}
        self._new: list[str] = []  # keys added since the last refresh, to bring into view
        self._count = itertools.count()
        self._widths: dict[str, int] = {}
        self._filter = ""  # as typed
        self._needle = ""  # as matched
        self._hide_io = False
        #: In a cell: the target whose IO rows the I/O grid shows (hidden here then).
        self.io_target: str | None = None
        self.sort_mode = SortMode.ADDED
        self._title: Text | None = None
        self._now = 0.0  # the clock of the last refresh, for a re-filter between two
        #: Rows out of view not brought up to date by the last refreshes (see refresh_rows).
        self._stale: set[str] = set()
        #: Rows to bring into view once the table has measured them (first, last, tries).
        self._reveal: tuple[int, int, int] | None = None
        #: Rows just brought into view (first and last key) and the scroll that showed
        #: them: kept in view while the layout changes under them and nothing scrolls.
        self._revealed: tuple[str, str, float] | None = None

    def on_mount(self) -> None:
        for key, label in self.columns_shown:
            # As Text: a str label is read as markup, which loads Rich's emoji table.
            self.add_column(Text(label), key=key)
        self._update_title()
        self.show_cursor = False

    def on_focus(self) -> None:
        """The row cursor shows only while keys go to the table: elsewhere a highlighted
        row would read as selected, and it would hide that row's colours."""
        self.show_cursor = True
        self._say_cut()

    def on_blur(self) -> None:
        self.show_cursor = False
        self._say_cut()

    # ------------------------------------------------------------- choices

    def set_filter(self, text: str) -> None:
        """Show only rows whose name or label contains ``text`` (any case)."""
        self._filter = text
        self._needle = needle_of(text)
        self._apply()

    @property
    def filter_text(self) -> str:
        return self._filter

    @property
    def title_text(self) -> str:
        """The border title as plain text: the filter, rows shown of all, the sort."""
        return self._title.plain if self._title is not None else ""

    def set_hide_io(self, hidden: bool) -> None:
        """Hide all IO rows (while an I/O bit grid shows them), with the filter still applied."""
        self._hide_io = hidden
        self._apply()

    def action_cycle_sort(self) -> None:
        self.sort_mode = self.sort_mode.next()
        self._apply()

    def action_cycle_field(self) -> None:
        key = self._cursor_key()
        if key is not None:
            self.cycle_field(self._owner[key])
            self._apply()

    def cycle_field(self, row: RowKey) -> None:
        """The next field of a V P J T row's trend (X → Y → Z → …); others have one."""
        labels = field_labels(row[1].kind)
        if labels:
            self.fields[row] = (self.fields.get(row, 0) + 1) % len(labels)

    def field_of(self, row: RowKey) -> int:
        return self.fields.get(row, 0)

    def action_row(self, action: str) -> None:
        self.post_message(self.RowAction(action, self.cursor_view(), self.cursor_target()))

    def cursor_view(self) -> RowView | None:
        key = self._cursor_key()
        return self._views.get(key) if key is not None else None

    def cursor_target(self) -> str:
        """The target of the row under the cursor ("" on an empty table)."""
        key = self._cursor_key()
        return self._owner[key][0] if key is not None and key in self._owner else ""

    def _cursor_key(self) -> str | None:
        if not self._order:
            return None
        return self._order[min(max(self.cursor_row, 0), len(self._order) - 1)]

    # ------------------------------------------------------------- refresh

    def refresh_rows(
        self,
        groups: Sequence[tuple[str, Mapping[VarRef, RowView]]],
        removed: set[RowKey],
        now: float,
    ) -> None:
        """Bring the table in line with the rows (ages, trends and the change highlight
        move with the clock); untouched cells are not redrawn. The rows in view are
        brought up to date each time, the others OFF_VIEW_PER_REFRESH at a time, in turn
        (and as they scroll into view): under a flood, 200 rows' cells built 30 times a
        second took most of the UI's time, for a dozen rows seen; built all at once every
        half second, they made the keys typed then wait."""
        cell = bool(self.cell)
        if removed:  # the rows waiting to be shown are counted in the old order
            self._reveal = self._revealed = None
        for name, var in removed:
            key = table_key(name, var, cell)
            self._added.pop(key, None)
            self._views.pop(key, None)
            self._owner.pop(key, None)
            self._target_plain.pop(key, None)
            self._stale.discard(key)
            self.fields.pop((name, var), None)
        views, added, owner = self._views, self._added, self._owner
        for name, rows in groups:
            for row in rows.values():
                key = table_key(name, row.var, cell) if cell else row.key
                if key not in added:
                    added[key] = next(self._count)
                    self._new.append(key)
                    owner[key] = (name, row.var)
                views[key] = row
        self._apply(now, every_row=False)
        self._say_cut()
        new, self._new = self._new, []
        shown = [n for n, key in enumerate(self._order) if key in set(new)]
        if shown:  # once laid out: the rows' room is known then
            self.call_after_refresh(self.reveal_rows, shown[0], shown[-1])

    def _say_cut(self) -> None:
        """When the values are wider than the table (a P row at 120 columns), the
        bottom border says how to read a row whole."""
        cut = self.virtual_size.width > self.scrollable_content_region.width
        subtitle = (CUT_FOCUSED if self.has_focus else CUT_HINT) if cut else ""
        if subtitle != str(self.border_subtitle or ""):
            self.border_subtitle = subtitle

    def on_resize(self) -> None:
        self._say_cut()
        self._show_stale()

    def watch_scroll_y(self, old_value: float, new_value: float) -> None:
        super().watch_scroll_y(old_value, new_value)
        self._show_stale()

    def _in_view(self) -> range:
        """The indices of the rows in view (and a few either side)."""
        top = int(self.scroll_y)
        room = max(self.scrollable_content_region.height, 0) + 2 * VIEW_MARGIN
        return range(max(top - VIEW_MARGIN, 0), top - VIEW_MARGIN + room)

    def _show_stale(self) -> None:
        """Rows come into view up to date (the view moved, or grew)."""
        if not self._stale:
            return
        order = self._order
        for n in self._in_view():
            if n >= len(order):
                break
            key = order[n]
            if key in self._stale:
                self._stale.discard(key)
                self._show(key, self._views[key], self._now)

    def reveal_rows(self, first: int, last: int, tries: int = REVEAL_TRIES) -> None:
        """Bring rows just added into view (``watch I 0-99`` below the rows there): all
        of them when they fit, else the first; the least scroll that does it. The
        cursor stays where it is. Until the table has measured its new rows it cannot
        scroll that far: then again each time it measures, a few times at most."""
        self._reveal = self._revealed = None
        room = self._rows_room()
        if room <= 0:
            return
        top = round(self.scroll_y)
        # All of them with the least scroll when they fit; else the first at the top.
        target = min(max(top, last - room + 1), first) if last - first < room else first
        if target > self.max_scroll_y and tries > 0:
            self._reveal = (first, last, tries - 1)
        else:
            if target != top:
                # force: the layout that shows the scrollbar may not have run yet.
                self.scroll_to(y=target, animate=False, immediate=True, force=True)
            order = self._order
            if last < len(order):
                self._revealed = (order[first], order[last], self.scroll_y)

    def _rows_room(self) -> int:
        """The rows in view once laid out: the region less the header, and less the
        horizontal scrollbar that values wider than the table call for, which the
        layout after a measuring has not always shown yet."""
        region = self.scrollable_content_region
        room = region.height - (self.header_height if self.show_header else 0)
        if not self.show_horizontal_scrollbar and self.virtual_size.width > region.width:
            room -= self.styles.scrollbar_size_horizontal
        return room

    def watch_virtual_size(self) -> None:
        """The table measured its rows: rows waiting to be shown can be scrolled to
        (after the refresh that lays the new size out)."""
        if self._reveal is not None:
            self.call_after_refresh(self._reveal_waiting)

    def watch_show_vertical_scrollbar(self, shown: bool) -> None:
        if shown:  # scrolled while it was hidden: its thumb where the view is
            self.vertical_scrollbar.position = self.scroll_y
        self._scrollbars_changed()

    def watch_show_horizontal_scrollbar(self, shown: bool) -> None:
        self._scrollbars_changed()

    def _scrollbars_changed(self) -> None:
        """The layout showed (or hid) a scrollbar: the room the rows waiting to be shown
        are measured against has changed; the rows just shown may have lost a line to
        it (their values came and the table grew wider than its pane)."""
        if self._reveal is not None:
            self.call_after_refresh(self._reveal_waiting)
        elif self._revealed is not None:
            self.call_after_refresh(self._keep_revealed)

    def _keep_revealed(self) -> None:
        """The rows just shown, in view again unless the view was scrolled since."""
        if self._revealed is None or self._reveal is not None:
            return
        first, last, shown_at = self._revealed
        if self.scroll_y != shown_at or first not in self._order or last not in self._order:
            self._revealed = None
            return
        self.reveal_rows(self._order.index(first), self._order.index(last), tries=0)

    def _reveal_waiting(self) -> None:
        """The rows waiting to be shown then (newer rows may have taken their turn)."""
        if self._reveal is not None:
            self.reveal_rows(*self._reveal)

    def _apply(self, now: float | None = None, *, every_row: bool = True) -> None:
        """Show the rows that pass the filter, in order, keeping the cursor on its
        variable; ``every_row`` False: the rows out of view are only marked stale."""
        if now is None:
            now = self._now
        self._now = now
        cursor = self._cursor_key()
        groups = (
            {key: (self._places.get(name, 0), name) for key, (name, _) in self._owner.items()}
            if self.cell
            else None
        )
        wanted = ordered_keys(
            self._views,
            self._added,
            self.sort_mode,
            self._needle,
            self._hide_io,
            groups,
            self.io_target if self.cell else None,
        )
        keep = set(wanted)
        for key in [key for key in self._order if key not in keep]:
            self.remove_row(key)
            del self._shown[key]
        self._order = [key for key in self._order if key in keep]
        if every_row:
            self._stale.clear()
            for key in wanted:
                self._show(key, self._views[key], now)
        else:
            in_view = self._in_view()
            shown, stale = self._shown, self._stale
            for n, key in enumerate(wanted):
                if n in in_view or key not in shown:  # a new row is added at once
                    stale.discard(key)
                    self._show(key, self._views[key], now)
                else:
                    stale.add(key)
            for key in list(islice(stale, OFF_VIEW_PER_REFRESH)):  # the rest, in turn
                stale.discard(key)
                self._show(key, self._views[key], now)
        if self._order != wanted:  # only a real change of order costs a sort
            if self.cell:  # the sort sees cells: a row is its target's and its variable's
                ranks = {
                    (self._target_plain[k], str(self._owner[k][1])): n for n, k in enumerate(wanted)
                }
                self.sort("target", "var", key=lambda cells: ranks[(cells[0].plain, cells[1])])
            else:
                rank = {key: n for n, key in enumerate(wanted)}
                self.sort("var", key=lambda key: rank[key])
            self._order = wanted
        if cursor is not None and cursor in keep:
            index = self._order.index(cursor)
            if index != self.cursor_row:
                self.move_cursor(row=index, animate=False)
        self._update_title()

    def _show(self, key: str, row: RowView, now: float) -> None:
        name = self._owner[key][0] if key in self._owner else ""
        target: tuple[object, ...] = ()
        if self.cell:
            shown_name = target_cell(name, self._colours.get(name))
            self._target_plain[key] = shown_name.plain
            target = (shown_name,)
        trend = trend_cell(row, self.trends(name), self.field_of((name, row.var)))
        cells = (*target, *row_cells(row, now, trend, self.app.current_theme.dark))
        shown = self._shown.get(key)
        if shown is None:
            self.add_row(*cells, key=key)
            self._order.append(key)
        else:
            for (column, _), old, new in zip(self.columns_shown, shown, cells, strict=True):
                if differs(old, new):
                    # Widening costs a pass over every row: only when a column grows.
                    width = len(str(new))
                    wider = width > self._widths.get(column, 0)
                    if wider:
                        self._widths[column] = width
                    self.update_cell(key, column, new, update_width=wider)
        self._shown[key] = cells

    def _update_title(self) -> None:
        typed = self._filter if self._needle else ""
        shown = (len(self._order), len(self._views))
        title = table_title(typed, self._hide_io, shown, self.sort_mode.value)
        if title != self._title:
            self._title = title
            self.border_title = title


class TableFilter(FilterLine):
    """The watch table's filter line, shown by ``/``: rows by name or label."""

    def __init__(self, table: WatchTable, **kwargs: object) -> None:
        super().__init__(table, "filter rows: name or label", **kwargs)
        table.filter_line = self  # ``/`` on the table opens this line at once
