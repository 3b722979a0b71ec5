"""Cells of a watch table (values per type, statuses), for the console and the REPL."""

from __future__ import annotations

from rich.text import Text

from .protocol import Variant, vt_name
from .protocol.text import scalar_text
from .watch import OK, WatchRow

HIGHLIGHT_SECONDS = 1.0


def number_text(value: object, label: str = "") -> str:
    """Numbers aligned: floats with 2 decimals in 8 columns; Fig as an integer."""
    if isinstance(value, float):
        if label == "Fig":
            return f"{int(value):>2d}"
        return f"{value:>8.2f}"
    if isinstance(value, bool):
        return "ON" if value else "OFF"
    if isinstance(value, int):
        return f"{value:>8d}"
    return scalar_text(value)


def value_cell(row: WatchRow, now: float) -> Text:
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
            text.append(number_text(value, label))
    elif kind.code == "IO":
        on = bool(variant.value)
        text.append(" ON " if on else " OFF", style="bold green" if on else "red")
    else:
        text.append(number_text(variant.value))
    if row.stale:
        text.stylize("dim italic")
    elif row.changed_at is not None and now - row.changed_at < HIGHLIGHT_SECONDS:
        text.stylize("bold on #4a4a10")
    return text


def status_cell(row: WatchRow) -> Text:
    if row.status == OK:
        return Text("OK", style="green", no_wrap=True)
    if row.stale:
        return Text(f"{row.status} (stale)", style="bold red", no_wrap=True)
    return Text(row.status, style="dim", no_wrap=True)


def type_text(row: WatchRow) -> str:
    variant: Variant | None = row.variant
    return vt_name(variant.vt if variant is not None else row.var.kind.vt)
