"""What a watch-table row shows, cell by cell, and the table's title: pure functions of
a row's view, so the table (:mod:`.watch_table`) only decides which rows to redraw."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.text import Text

from ..present.filtering import add_filter_title
from ..present.status import label_style
from ..present.table_cells import age_text, change_style, status_cell, type_text, value_cell
from ..present.trends import field_labels, has_trend, sparkline_text
from ..protocol.text import terminal_safe

if TYPE_CHECKING:
    from ..engine.published.events import RowView
    from ..present.trends import TrendStore

#: Bars in a trend cell; a field's label (``Rz``, ``Fig``) takes the first 4 cells.
SPARK_WIDTH = 16
FIELD_WIDTH = 4


def target_cell(name: str, colour: str | None) -> Text:
    """A cell's target column: the name on its profile's colour (a name from the config
    file: never raw to the screen)."""
    style = label_style(colour) if colour else "bold"
    return Text(f" {terminal_safe(name)} ", style=style, no_wrap=True)


def row_cells(row: RowView, now: float, trend: Text, dark: bool) -> tuple[object, ...]:
    """The row's cells after the target: variable, label, status, age, trend, value,
    VARTYPE (the value legible on a light theme too)."""
    return (
        str(row.var),
        Text(terminal_safe(row.label), no_wrap=True),  # never read as markup
        status_cell(row),
        age_text(row, now),
        trend,
        value_cell(row, now, change_style(dark)),
        type_text(row),
    )


def trend_cell(row: RowView, trends: TrendStore, field: int) -> Text:
    """The row's recent values as a sparkline (a position's field named first)."""
    var = row.var
    if not has_trend(var.kind) or var not in trends:
        return Text("")
    labels = field_labels(var.kind)
    text = Text(no_wrap=True, overflow="crop")
    width = SPARK_WIDTH
    if labels:
        text.append(f"{labels[field]:<{FIELD_WIDTH - 1}} ", style="dim")
        width -= FIELD_WIDTH
    io = var.kind.code == "IO"
    values = trends.last(var, field, width)
    bars = sparkline_text(values, width, *((0.0, 1.0) if io else (None, None)))
    text.append(bars, style="dim" if row.stale else "cyan")
    return text


def table_title(typed: str, io_hidden: bool, shown: tuple[int, int], sort: str) -> Text:
    """``Watch  3 of 10 rows (IO hidden)  sort: name``: the filter as typed, how many
    rows of all pass it, and the sort."""
    count, total = shown
    title = Text("Watch")
    if typed:
        add_filter_title(title, typed)
    if typed or io_hidden:
        title.append(f"  {count} of {total} rows")
    else:
        title.append(f"  {total} row{'s' * (total != 1)}")
    if io_hidden:
        title.append(" (IO hidden)")
    title.append(f"  sort: {sort}")
    return title


def differs(old: object, new: object) -> bool:
    """Whether a cell must be drawn again (a Text by its text and styles)."""
    if isinstance(old, Text) and isinstance(new, Text):
        return old.plain != new.plain or old.spans != new.spans
    return old != new
