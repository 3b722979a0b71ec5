"""Cells of a watch table (values per type, statuses, ages), for the console and the REPL."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rich.text import Text

from ..engine.published.status import OK, WAITING
from ..protocol.text import scalar_text, terminal_safe
from ..protocol.vartypes import vt_name

if TYPE_CHECKING:
    from rich.table import Table

    from ..commands.language import VarRef
    from ..engine.published.events import RowView
    from ..protocol.variant import Variant

HIGHLIGHT_SECONDS = 1.0


@dataclass(frozen=True, slots=True)
class ChangeStyle:
    """How a value that changed within :data:`HIGHLIGHT_SECONDS` stands out (table and
    I/O grid): a background, and text that reads on it in the theme it is made for."""

    value: str  # over a changed value: a table cell, an I/O grid's word
    io_on: str  # then over the table's ON
    io_off: str  # and its OFF
    bit_on: str  # a changed ON bit in the I/O grid (its whole style)
    bit_off: str  # a changed OFF bit


#: On a dark theme (and the REPL's terminal, whatever its colours): white on olive (a
#: theme's own text can be too pale on it: solarized-dark's is under 3:1), ON light
#: green, OFF light red (the terminal's red is too dark on it), each above 4:1.
CHANGED_DARK = ChangeStyle(
    value="bold #ffffff on #4a4a10",
    io_on="#87d787",
    io_off="#ff8a80",
    bit_on="bright_green bold on #4a4a10",
    bit_off="#b0b0b0 on #4a4a10",
)
#: On a light theme, whose dark text is lost on olive (1.8:1 in textual-light): pale
#: amber under near-black text, ON dark green, OFF dark red (grey in the grid, as OFF
#: is there), each above 5:1. No ``dim``: it blends the text into the background.
CHANGED_LIGHT = ChangeStyle(
    value="bold #1a1a1a on #ffe082",
    io_on="#006b1f",
    io_off="#a40000",
    bit_on="bold #006b1f on #ffe082",
    bit_off="#555555 on #ffe082",
)


def change_style(dark: bool) -> ChangeStyle:
    """The change highlight for a dark or a light theme (the console asks its theme)."""
    return CHANGED_DARK if dark else CHANGED_LIGHT


#: Numbers are right-aligned in at least this many columns; a longer one widens its cell.
NUMBER_WIDTH = 8


def number_text(value: object, width: int = NUMBER_WIDTH) -> str:
    """The value exactly as ``get`` shows it (shortest round-trip text, an exponent
    when long: 0.000123, 1e+300, -3.3e+38), right-aligned so fields line up."""
    if isinstance(value, bool):
        return "ON" if value else "OFF"
    return f"{scalar_text(value):>{width}}"


def value_cell(row: RowView, now: float, change: ChangeStyle = CHANGED_DARK) -> Text:
    variant = row.variant
    if variant is None:
        return Text("—", style="dim")
    kind = row.var.kind
    text = Text(no_wrap=True, overflow="crop")
    if kind.labels and isinstance(variant.value, list) and len(variant.value) == kind.count:
        for n, (label, value) in enumerate(zip(kind.labels, variant.value, strict=True)):
            if n:
                text.append(" ")
            text.append(label + " ", style="dim")
            text.append(number_text(value, 2 if label == "Fig" else NUMBER_WIDTH))
    elif kind.code == "IO":
        on = bool(variant.value)
        text.append(" ON " if on else " OFF", style="bold green" if on else "red")
    else:
        text.append(number_text(variant.value))
    if row.stale:
        text.stylize("dim italic")
    elif row.changed_at is not None and now - row.changed_at < HIGHLIGHT_SECONDS:
        text.stylize(change.value)
        if kind.code == "IO":
            text.stylize(change.io_on if variant.value else change.io_off)
    return text


def status_cell(row: RowView) -> Text:
    if row.status == OK:
        return Text("OK", style="green", no_wrap=True)
    if row.stale:
        return Text(f"{row.status} (stale)", style="bold red", no_wrap=True)
    if row.status != WAITING:  # failed before any value came
        return Text(row.status, style="bold red", no_wrap=True)
    return Text(row.status, style="dim", no_wrap=True)


def type_text(row: RowView) -> str:
    variant: Variant | None = row.variant
    return vt_name(variant.vt if variant is not None else row.var.kind.vt)


def age_text(row: RowView, now: float) -> str:
    """How long ago the value changed: ``<1s``, ``42s``, ``3m07s``, ``2h05m``."""
    if row.changed_at is None:
        return ""
    age = max(0.0, now - row.changed_at)
    if age < 1:
        return "<1s"
    if age < 60:
        return f"{int(age)}s"
    if age < 3600:
        return f"{int(age // 60)}m{int(age % 60):02d}s"
    return f"{int(age // 3600)}h{int(age % 3600 // 60):02d}m"


def watch_table(
    variables: Sequence[VarRef],
    rows: Mapping[VarRef, RowView],
    paused: bool,
    title: str | None = None,
) -> Table:
    """The REPL's live watch: the watched rows; while polling is paused each says so (a
    row never read says "not polled", not a blank that never fills)."""
    from rich.table import Table

    table = Table(box=None, pad_edge=False, header_style="bold", title=title)
    for heading in ("Variable", "Label", "Status", "Changed", "Value"):
        table.add_column(heading)
    now = time.monotonic()
    for var in variables:
        row = rows.get(var)
        if row is not None:
            value = value_cell(row, now)
            if paused and row.variant is None:
                value = Text("not polled", style="dim italic")
            table.add_row(
                str(var),
                Text(terminal_safe(row.label)),
                Text("paused", style="bold yellow") if paused else status_cell(row),
                age_text(row, now),
                value,
            )
    return table
