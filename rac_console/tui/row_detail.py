"""The row under the table's cursor in full (``d`` on a row), in the frame log's place.

A position row is cut by the table at 80 and at 120 columns; here each field has a line
of its own (in columns of three when the lines do not fit), each value whole. It follows
the cursor and the polls; a field that changed in the last second is highlighted, so a
moving axis stands out. Drawn by :mod:`rac_console.present.row_detail`; it takes no
focus, so the arrows keep moving the table's cursor while it shows.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.text import Span, Text
from textual import events
from textual.widgets import Static

from ..present.row_detail import detail_fields, detail_text, header_text
from ..present.table_cells import HIGHLIGHT_SECONDS, change_style

if TYPE_CHECKING:
    from ..commands.language import VarRef
    from ..engine.published.events import RowView

EMPTY_TEXT = Text("No rows: watch P 0 adds one; d on a row shows it here", style="dim")
SUBTITLE = "d or Esc closes · ↑↓ in the table: another row"


class RowDetail(Static):
    """Shown while open (the console adds ``-open``) and calls :meth:`show_row` with the
    row under the cursor at the table's refresh rate and when the cursor moves."""

    def __init__(self, **kwargs: str | None) -> None:
        super().__init__(EMPTY_TEXT, **kwargs)  # type: ignore[arg-type]
        self.row: RowView | None = None
        self.shown_text = ""  # what it shows, as plain text
        self._var: VarRef | None = None
        self._values: list[str] = []
        self._changed_at: dict[int, float] = {}
        self._now = 0.0
        self._spans: list[Span] = []
        self._title: Text | None = None

    def on_mount(self) -> None:
        self.border_title = "Row"
        self.border_subtitle = SUBTITLE

    @property
    def is_open(self) -> bool:
        return self.has_class("-open")

    def show_row(self, row: RowView | None, now: float) -> None:
        """Draw ``row`` (None: the table is empty); fields whose value differs from the
        one drawn before are marked changed from ``now``."""
        self.row, self._now = row, now
        if row is None:
            self._var, self._values = None, []
            self._changed_at.clear()
            self._title = None
            self.border_title = "Row"
            self._draw(EMPTY_TEXT)
            return
        if row.var != self._var:  # another row: nothing of the last one is a change
            self._var = row.var
            self._values = []
            self._changed_at.clear()
        title = header_text(row, now)
        if title != self._title:
            self._title = title
            self.border_title = title
        values = [value for _, value in detail_fields(row)]
        if len(values) == len(self._values):
            for n, (old, new) in enumerate(zip(self._values, values, strict=True)):
                if old != new:
                    self._changed_at[n] = now
        self._values = values
        changed = {n for n, at in self._changed_at.items() if now - at < HIGHLIGHT_SECONDS}
        height = self.content_region.height or len(values)
        theme = change_style(self.app.current_theme.dark)  # legible on a light theme too
        self._draw(detail_text(row, now, height, changed, theme))

    def _draw(self, text: Text) -> None:
        """Only when the words or their styles changed (5 times a second otherwise)."""
        if text.plain != self.shown_text or text.spans != self._spans:
            self.shown_text, self._spans = text.plain, list(text.spans)
            self.update(text)

    def on_resize(self, event: events.Resize) -> None:
        """Lines or columns of fields, for the new height."""
        if self.is_open:
            self.show_row(self.row, self._now)
