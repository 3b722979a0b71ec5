"""Which watched rows a table shows, and in what order: filter, hidden IO, sort.

Pure, so the console's table only applies the result (and re-sorts only when the
order it computes differs from the one on screen).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from enum import Enum
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..commands.language import VarRef
    from ..engine.published.events import RowView

#: A row of a cell's table: its target's name and its variable (``I 10`` on two targets
#: is two rows).
RowKey = tuple[str, "VarRef"]


def table_key(name: str, var: VarRef, cell: bool) -> str:
    """A row's key in the table: the variable (``P10``), in a cell after its target
    (``robotA P10``)."""
    return f"{name} {var}" if cell else str(var)


class SortMode(Enum):
    ADDED = "as added"
    NAME = "name"
    CHANGED = "last change"

    def next(self) -> SortMode:
        modes = list(SortMode)
        return modes[(modes.index(self) + 1) % len(modes)]


def matches(row: RowView, needle: str, target: str = "") -> bool:
    """The filter: the variable's name (``P10``), its label or (in a cell) its target's
    name contains the text, any case."""
    return (
        not needle
        or needle in row.key.lower()
        or needle in row.label.lower()
        or (bool(target) and needle in target.lower())
    )


def visible_keys(
    rows: Iterable[RowView],
    added: dict[str, int],
    mode: SortMode,
    needle: str = "",
    hide_io: bool = False,
) -> list[str]:
    """Row keys to show, in order. ``added`` numbers the keys in the order they came;
    ``needle`` is the filter text, lower-cased."""
    return ordered_keys({row.key: row for row in rows}, added, mode, needle, hide_io)


def ordered_keys(
    views: Mapping[str, RowView],
    added: dict[str, int],
    mode: SortMode,
    needle: str = "",
    hide_io: bool = False,
    groups: Mapping[str, tuple[int, str]] | None = None,
    io_of: str | None = None,
) -> list[str]:
    """:func:`visible_keys` over rows by key; ``groups`` (a cell's table) gives each key
    its target's place in the cell and name: rows go by target first, in cell order,
    then in the sort's order within each target. ``io_of``: in a cell, ``hide_io``
    hides only this target's IO rows (the ones the I/O grid shows)."""
    group = groups or {}

    def where(key: str) -> tuple[int, str]:
        return group.get(key, (0, ""))

    shown = [
        key
        for key, row in views.items()
        if matches(row, needle, where(key)[1])
        and not (
            hide_io and row.var.kind.code == "IO" and (io_of is None or where(key)[1] == io_of)
        )
    ]
    if mode is SortMode.NAME:
        shown.sort(key=lambda key: (where(key)[0], views[key].var.kind.code, views[key].var.index))
    elif mode is SortMode.CHANGED:  # the most recent first; never changed last

        def recent(key: str) -> tuple[int, float, int]:
            changed = views[key].changed_at
            return (
                where(key)[0],
                -(changed if changed is not None else -math.inf),
                added.get(key, 0),
            )

        shown.sort(key=recent)
    else:
        shown.sort(key=lambda key: (where(key)[0], added.get(key, 0)))
    return shown
