"""One watched row in full, a field a line: what the table cuts on a narrow terminal.

A P row needs about 130 columns in the table; at 120 it is cut after Ry, at 80 only X and
Y show. As mycli's ``\\G`` prints a row one column per line, the console's detail view
(``d`` on a row) shows the row under the cursor as ``X  350``, ``Y  0``, … (J1..J8, the
10 fields of a T), each value whole, as ``get`` prints it. When the lines do not fit the
height, the fields go in columns of three (X Y Z | Rx Ry Rz | Fig), the way the
fields group; the header (status, age, type) goes in the view's border. Pure (rich only
for the finished text), so it is tested without a screen.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import TYPE_CHECKING

from rich.text import Text

from ..engine.published.status import OK
from ..protocol.text import scalar_text, terminal_safe
from .table_cells import CHANGED_DARK, ChangeStyle, age_text, type_text

if TYPE_CHECKING:
    from ..engine.published.events import RowView

#: Fields a column holds when they do not fit a line each: X Y Z | Rx Ry Rz | Fig.
GROUP = 3
#: Blanks between two columns of fields.
COLUMN_GAP = 4
NO_VALUE = "no value yet"


def detail_fields(row: RowView) -> list[tuple[str, str]]:
    """The row's fields as (label, value) in the order the type defines them; one
    ``value`` field for a scalar, a bit or a string."""
    variant = row.variant
    if variant is None:
        return [("value", NO_VALUE)]
    kind = row.var.kind
    value = variant.value
    if kind.labels and isinstance(value, list) and len(value) == kind.count:
        return [(label, scalar_text(v)) for label, v in zip(kind.labels, value, strict=True)]
    if kind.code == "IO":
        return [("value", "ON" if value else "OFF")]
    return [("value", scalar_text(value))]


def header_text(row: RowView, now: float) -> Text:
    """``P10  pick  OK  changed 3s ago  VT_R4|VT_ARRAY``: what the table says of it."""
    text = Text(no_wrap=True, overflow="ellipsis", end="")
    text.append(row.key, style="bold")
    if row.label:
        text.append(f"  {terminal_safe(row.label)}")
    if row.status == OK:
        text.append("  OK", style="green")
    else:
        status = f"{row.status} (stale)" if row.stale else row.status
        text.append(f"  {status}", style="bold red" if row.stale else "dim")
    age = age_text(row, now)
    if age:
        text.append(f"  changed {age} ago", style="dim")
    text.append(f"  {type_text(row)}", style="dim")
    return text


def columns_for(count: int, height: int) -> int:
    """How many columns ``count`` fields take in ``height`` lines: one while a line
    each fits, else columns of :data:`GROUP` (fewer lines when even those do not fit)."""
    if count <= max(height, 1):
        return 1
    rows = GROUP if height >= GROUP else max(height, 1)
    return -(-count // rows)


def detail_text(
    row: RowView,
    now: float,
    height: int,
    changed: Collection[int] = (),
    change: ChangeStyle = CHANGED_DARK,
) -> Text:
    """The fields in ``height`` lines (the header goes in the view's border): a label
    and its value right-aligned under the others; the fields in ``changed`` (indices)
    highlighted with ``change`` (the theme's); a stale value dim and italic, as in the
    table. A string is shown whole, to be wrapped by the view."""
    text = Text(end="")
    fields = detail_fields(row)
    value_style = "dim italic" if row.stale else "bold"
    if row.var.kind.code == "S" and row.variant is not None:
        text.append(fields[0][1], style=change.value if changed and not row.stale else value_style)
        return text
    columns = columns_for(len(fields), height)
    per_column = -(-len(fields) // columns)
    label_width = max(len(label) for label, _ in fields)
    groups = [fields[at : at + per_column] for at in range(0, len(fields), per_column)]
    widths = [max(len(value) for _, value in group) for group in groups]
    for line in range(per_column):
        if line:
            text.append("\n")
        for column, group in enumerate(groups):
            if line >= len(group):
                continue
            label, value = group[line]
            if column:
                text.append(" " * COLUMN_GAP)
            index = column * per_column + line
            text.append(f"{label:<{label_width}}  ", style="dim")
            style = change.value if index in changed and not row.stale else value_style
            text.append(f"{value:>{widths[column]}}", style=style)
    return text
