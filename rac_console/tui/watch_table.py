"""The live watch table: keyed rows, updated in place, only the cells that changed."""

from __future__ import annotations

from rich.text import Text
from textual.widgets import DataTable

from ..commands.language import VarRef
from ..engine import RowView
from ..present.cells import age_text, status_cell, type_text, value_cell
from ..protocol.text import terminal_safe

#: Status and age before the value, so they stay in view when a long P or J value is
#: cut off on a narrow terminal.
COLUMNS = (
    ("var", "Variable"),
    ("label", "Label"),
    ("status", "Status"),
    ("changed", "Changed"),
    ("value", "Value"),
    ("type", "VARTYPE"),
)


class WatchTable(DataTable[object]):
    """Rows are keyed by variable name (``P10``); the app calls :meth:`refresh_rows` at ~5 Hz."""

    def __init__(self, **kwargs: object) -> None:
        super().__init__(cursor_type="row", zebra_stripes=True, **kwargs)  # type: ignore[arg-type]
        self._shown: dict[str, tuple[object, ...]] = {}
        self._widths: dict[str, int] = {}

    def on_mount(self) -> None:
        for key, label in COLUMNS:
            self.add_column(label, key=key)

    def refresh_rows(self, rows: dict[VarRef, RowView], removed: set[VarRef], now: float) -> None:
        """Bring the table in line with the rows (every row, each time: ages and the
        change highlight move with the clock); untouched cells are not redrawn."""
        for var in removed:
            key = str(var)
            if key in self._shown:
                self.remove_row(key)
                del self._shown[key]
        for var, row in rows.items():
            key = str(var)
            cells = (
                key,
                Text(terminal_safe(row.label), no_wrap=True),  # never read as markup
                status_cell(row),
                age_text(row, now),
                value_cell(row, now),
                type_text(row),
            )
            shown = self._shown.get(key)
            if shown is None:
                self.add_row(*cells, key=key)
            else:
                for (column, _), old, new in zip(COLUMNS, shown, cells, strict=True):
                    if _differs(old, new):
                        # Widening costs a pass over every row: only when a column grows.
                        width = len(str(new))
                        wider = width > self._widths.get(column, 0)
                        if wider:
                            self._widths[column] = width
                        self.update_cell(key, column, new, update_width=wider)
            self._shown[key] = cells


def _differs(old: object, new: object) -> bool:
    if isinstance(old, Text) and isinstance(new, Text):
        return old.plain != new.plain or old.spans != new.spans
    return old != new
