"""The I/O panel: watched IO bits as a grid (F5), beside the table or under it.

The grid is built by :mod:`rac_console.present.iogrid`; this widget only draws it when
its text changed, at the table's refresh rate. Its cursor's Space asks the console to write
the opposite of the bit shown, which it does as for a table row: through
:meth:`Engine.submit`, like a typed line, with one write per bit in flight.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, ClassVar

from rich.text import Text
from textual import events
from textual.app import ComposeResult
from textual.binding import BindingType
from textual.containers import Container, VerticalScroll
from textual.geometry import Region
from textual.message import Message
from textual.widget import Widget
from textual.widgets import DataTable, Static

from ..present.table_cells import change_style
from ..protocol.text import terminal_safe
from . import keys

if TYPE_CHECKING:  # the grid is hidden until F5: its modules load when it first shows
    from ..commands.language import VarRef
    from ..engine.published.events import RowView
    from ..present.iogrid import Grid

#: From this many columns the panel sits beside the table; below, under it.
WIDE_COLUMNS = 160

TITLE = "I/O (word: bit 0 = lowest index)"
EMPTY_TEXT = Text("No IO bits watched: try watch IO 128-143", style="dim", end="")


def _io(index: int) -> VarRef:
    """Bit ``index`` of the IO variables, as the rows are keyed."""
    from ..commands.language import VarRef
    from ..protocol.variables import kind_of

    return VarRef(kind_of("IO"), index)


def state_word(row: RowView) -> str:
    """``ON``, ``OFF`` or ``no value``, and ``(stale)`` when the last poll failed."""
    variant = row.variant
    word = "no value" if variant is None else ("ON" if bool(variant.value) else "OFF")
    return f"{word} (stale)" if row.stale else word


class WatchArea(Container):
    """The watch table and the I/O panel: the panel beside the table from
    :data:`WIDE_COLUMNS` when both fit whole (every column of the table, a line of 16
    bits), as wide as its grid can use (symbols, labels); under it otherwise.

    Half the width for one line of bits cut the position rows at 80 columns. The table's
    columns are as wide as their cells whatever room it has, and the grid's widths follow
    from the bits watched, so the choice never feeds back on itself.
    """

    def __init__(self, table: DataTable[object], panel: IoPanel, **kwargs: str | None) -> None:
        """The two it holds, as attributes: a timer never queries a DOM torn down."""
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.table = table
        self.panel = panel

    def compose(self) -> ComposeResult:
        yield self.table
        yield self.panel

    def on_resize(self, event: events.Resize) -> None:
        self.share_width()

    def share_width(self) -> None:
        """Beside or under, from the room there is; called as rows come and go."""
        panel, table = self.panel, self.table
        if not (self.is_mounted and table.is_mounted and panel.is_mounted):
            return
        width = self.size.width
        beside = False
        panel_width: int | None = None
        if panel.display and width >= WIDE_COLUMNS:
            least, most = panel.widths_wanted()
            room = width - _chrome(table) - table.virtual_size.width
            if room >= least:
                beside, panel_width = True, min(most, room)
        self.set_class(beside, "-wide")
        if panel_width != panel.arranged_width:
            panel.arranged_width = panel_width
            panel.styles.width = panel_width  # None: the stylesheet's, under the table


def _chrome(widget: Widget) -> int:
    """The columns a pane takes besides its content: border, padding, scrollbar."""
    return widget.styles.gutter.width + widget.styles.scrollbar_size_vertical


class IoPanel(VerticalScroll, can_focus=True):
    """The grid, scrolled when it has more lines than room; hidden until F5."""

    BINDINGS: ClassVar[list[BindingType]] = keys.IO_PANEL

    class Toggle(Message):
        """Space on a watched bit: the console writes its opposite (as a typed line)."""

        def __init__(self, row: RowView) -> None:
            super().__init__()
            self.row = row

    def __init__(self, busy: Callable[[VarRef], bool], **kwargs: str | None) -> None:
        """``busy`` says whether a bit's last toggle is still in flight (underlined)."""
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self._busy = busy
        self._body = Static(EMPTY_TEXT, id="io-grid")
        self._rows: Mapping[VarRef, RowView] = {}
        self._text: Text = EMPTY_TEXT
        self.grid: Grid | None = None
        self.cursor: int | None = None
        self.arranged_width: int | None = None  # set by the watch area while beside

    def widths_wanted(self) -> tuple[int, int]:
        """The panel's width for its grid at its best without labels, and with them."""
        from ..present.iogrid import widths_wanted

        plain, labelled = widths_wanted(self._rows)
        if not plain:
            plain = labelled = EMPTY_TEXT.cell_len
        chrome = _chrome(self)
        return plain + chrome, labelled + chrome

    def compose(self) -> ComposeResult:
        yield self._body

    def on_mount(self) -> None:
        self.border_title = TITLE

    def show(self, shown: bool) -> None:
        """Show or hide the grid; the watch area gives it room while it shows."""
        self.display = shown
        if self.parent is not None:
            self.parent.set_class(shown, "-io-grid")

    # ---------------------------------------------------------------- drawing

    def refresh_rows(self, rows: Mapping[VarRef, RowView], now: float) -> None:
        """Called with the table's refresh; costs nothing while the panel is hidden."""
        self._rows = rows
        if self.display:
            self._draw(now)

    def _draw(self, now: float) -> None:
        from ..present.iogrid import build_grid
        from ..protocol.variables import kind_of

        rows = self._rows
        io = kind_of("IO")
        grid = build_grid(
            rows,
            now,
            self.scrollable_content_region.width,
            self.cursor if self.has_focus else None,
            frozenset(var.index for var in rows if var.kind is io and self._busy(var)),
            change_style(self.app.current_theme.dark),  # legible on a light theme too
        )
        self.grid = grid
        text = grid.text if grid.lines else EMPTY_TEXT
        if text.plain != self._text.plain or text.spans != self._text.spans:
            self._text = text
            self._body.update(text)
        self._show_cursor_label()

    def _show_cursor_label(self) -> None:
        """The bit under the cursor, its state and its label in the bottom border: said
        in words there however narrow the cells are (the cursor's colour is its own)."""
        subtitle = Text()
        row = self._rows.get(_io(self.cursor)) if self.cursor is not None else None
        if self.has_focus and self.cursor is not None:
            subtitle.append(f"IO {self.cursor}")
            if row is None:
                subtitle.append(" not watched", style="dim")
            else:
                subtitle.append(f" {state_word(row)}")
                if row.label:
                    subtitle.append(f" {terminal_safe(row.label)}")
        if subtitle.plain != str(self.border_subtitle or ""):
            self.border_subtitle = subtitle

    def on_resize(self, event: events.Resize) -> None:
        if self.display:
            self._draw(time.monotonic())

    def on_focus(self, event: events.Focus) -> None:
        grid = self.grid
        if self.cursor is None and grid is not None and grid.lines:
            bits = [bit for line in grid.lines for bit in line.bits]
            self.cursor = next((b.index for b in bits if b.has_value), bits[0].index)
        self._draw(time.monotonic())

    def on_blur(self, event: events.Blur) -> None:
        self._draw(time.monotonic())

    # ---------------------------------------------------------------- actions

    def action_move(self, dx: int, dy: int) -> None:
        """Arrows: left and right run on through the lines, up and down keep the column."""
        grid = self.grid
        if grid is None or not grid.lines:
            return
        starts = [line.start for line in grid.lines]
        per_line = grid.layout.per_line
        cursor = self.cursor if self.cursor is not None else starts[0]
        row = next((n for n, start in enumerate(starts) if start <= cursor < start + per_line), 0)
        column = cursor - starts[row] + dx
        if column < 0 and row > 0:
            row, column = row - 1, per_line - 1
        elif column >= per_line and row < len(starts) - 1:
            row, column = row + 1, 0
        row = min(max(row + dy, 0), len(starts) - 1)
        column = min(max(column, 0), per_line - 1)
        self.cursor = starts[row] + column
        self._draw(time.monotonic())
        self.scroll_to_region(Region(0, row, 1, 1), animate=False, immediate=True)

    def action_toggle_bit(self) -> None:
        """Space: hand the bit under the cursor to the console, which refuses while its last
        toggle is in flight (a burst of Space must not write a value nobody meant)."""
        index = self.cursor
        if index is None or not self.has_focus:
            return
        row = self._rows.get(_io(index))
        if row is None:
            self.notify(f"IO {index} is not watched: nothing to toggle", severity="warning")
            return
        self.post_message(self.Toggle(row))
