"""Which watched rows a table shows, and in what order: filter, hidden IO, sort.

Pure, so the console's table only applies the result (and re-sorts only when the
order it computes differs from the one on screen).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from enum import Enum
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..engine.events import RowView


class SortMode(Enum):
    ADDED = "as added"
    NAME = "name"
    CHANGED = "last change"

    def next(self) -> SortMode:
        modes = list(SortMode)
        return modes[(modes.index(self) + 1) % len(modes)]


def matches(row: RowView, needle: str) -> bool:
    """The filter: the variable's name (``P10``) or its label contains the text, any case."""
    return not needle or needle in row.key.lower() or needle in row.label.lower()


def visible_keys(
    rows: Iterable[RowView],
    added: dict[str, int],
    mode: SortMode,
    needle: str = "",
    hide_io: bool = False,
) -> list[str]:
    """Row keys to show, in order. ``added`` numbers the keys in the order they came;
    ``needle`` is the filter text, lower-cased."""
    shown = [
        row for row in rows if matches(row, needle) and not (hide_io and row.var.kind.code == "IO")
    ]
    if mode is SortMode.NAME:
        shown.sort(key=lambda row: (row.var.kind.code, row.var.index))
    elif mode is SortMode.CHANGED:  # the most recent first; never changed last
        shown.sort(
            key=lambda row: (
                -(row.changed_at if row.changed_at is not None else -math.inf),
                added.get(row.key, 0),
            )
        )
    else:
        shown.sort(key=lambda row: added.get(row.key, 0))
    return [row.key for row in shown]
