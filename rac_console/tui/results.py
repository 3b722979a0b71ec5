"""The results pane: each command as typed and what came of it, wrapped to the width.

Textual's RichLog wraps a line once, for the width it has when the line is written (and
never narrower than its ``min_width``, 78 unless told: set to 1 here): after
the terminal narrowed, lines were cut at the right and a scrollbar hid the last one; after
it widened, short lines stayed broken. This one keeps what it was given (as many entries
as it shows lines) and writes them again, wrapped anew, when its width changes.
"""

from __future__ import annotations

from collections import deque
from typing import Self

from rich.console import RenderableType
from textual import events
from textual.widgets import RichLog

from .compat import limit_drawn_lines, rich_log_sized

#: Lines the pane keeps (and entries, each at least a line): about 6 KB a line with
#: Textual's caches, and 0.5 KB its entry; 3.3 MB when full.
MAX_LINES = 500
#: Lines kept as drawn (cut to the view), more than a pane shows on any screen; RichLog
#: keeps 1,024 (5 KB each) whatever the pane shows.
DRAWN_LINES = 200


class ResultsLog(RichLog):
    """Written to with :meth:`write` (plain Rich renderables, never markup)."""

    def __init__(self, **kwargs: str | None) -> None:
        # min_width: RichLog renders at 78 cells at least, which at 80 columns put the
        # last character of a wrapped line under the scrollbar ("J3 3." for "J3 3.5").
        super().__init__(
            max_lines=MAX_LINES,
            wrap=True,
            markup=False,
            highlight=False,
            min_width=1,
            **kwargs,  # type: ignore[arg-type]
        )
        limit_drawn_lines(self, DRAWN_LINES)
        self._entries: deque[RenderableType] = deque(maxlen=MAX_LINES)
        self._wrapped_for = 0  # the width the lines were wrapped for
        self._waiting = 0  # entries written before the first size: RichLog writes them again

    def write(
        self,
        content: RenderableType | object,
        width: int | None = None,
        expand: bool = False,
        shrink: bool = True,
        scroll_end: bool | None = None,
        animate: bool = False,
    ) -> Self:
        """One entry, kept to be wrapped again at another width (RichLog's own second
        write of an entry that came before the first size is not one more)."""
        if self._waiting and rich_log_sized(self):
            self._waiting -= 1
        else:
            self._entries.append(content)  # type: ignore[arg-type]  # Rich renderables only
            if not rich_log_sized(self):
                self._waiting += 1
        return super().write(content, width, expand, shrink, scroll_end, animate)

    def clear(self) -> Self:
        self._entries.clear()
        self._waiting = 0
        return super().clear()

    def on_resize(self, event: events.Resize) -> None:
        """Wrap every entry again for the new width, and stay at the end."""
        width = self.scrollable_content_region.width
        if width == self._wrapped_for:
            return
        first = not self._wrapped_for
        self._wrapped_for = width
        if first or not self._entries:
            return  # RichLog writes what waited for its first size itself
        entries = list(self._entries)
        super().clear()
        for entry in entries:
            super().write(entry, scroll_end=False)
        self.scroll_end(animate=False, immediate=True)
