"""The raw frame log: one line per frame, written in batches, bounded in memory."""

from __future__ import annotations

import time
from collections import deque
from typing import ClassVar

from rich.cells import cell_len
from textual.binding import Binding, BindingType
from textual.widgets import Log

from ..engine import Alert, Note
from ..present.frames import clock_text, frame_line
from ..protocol.text import terminal_safe
from ..session import Frame

MAX_LINES = 5000
MAX_PENDING = 50_000
#: Lines drawn per flush (10 a second) at most: past it only the newest are drawn, and one
#: line says how many were not (drawing them cost the poller its CPU, unread).
MAX_LINES_PER_FLUSH = 500


class FrameLog(Log):
    """Frames are queued as they cross the wire and written by :meth:`flush` at ~20 Hz:
    one ``write_lines`` per screen refresh instead of one per frame."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape", "app.focus_command_line", "Command line", id="log-leave"),
        Binding("tab", "app.focus_pane(1)", "Next pane", show=False, id="log-next-pane"),
        Binding("shift+tab", "app.focus_pane(-1)", "Previous pane", show=False, id="log-prev"),
    ]

    def __init__(self, **kwargs: object) -> None:
        super().__init__(max_lines=MAX_LINES, auto_scroll=True, **kwargs)  # type: ignore[arg-type]
        self._pending: deque[Frame | tuple[float, str]] = deque(maxlen=MAX_PENDING)
        self.show_polls = True

    def on_resize(self) -> None:
        """A resize moves the end away from the view: bring it back while following."""
        if self.auto_scroll:
            self.call_after_refresh(self.scroll_end, animate=False, x_axis=False)

    def add(self, event: Frame | Note | Alert) -> None:
        """Queue one event drained from the engine's outbox; cheap, written at the next flush.

        A note carries the time it happened, so it sits in time order among the frames
        around it.
        """
        if isinstance(event, Frame):
            self._pending.append(event)
        elif isinstance(event, Note):
            self._pending.append((event.time, event.text))
        else:
            self._pending.append((time.time(), event.text))

    def flush(self) -> int:
        """Write what arrived since the last flush; returns the number of events."""
        if not self._pending:
            return 0
        events = list(self._pending)
        self._pending.clear()
        shown = [e for e in events if not isinstance(e, Frame) or self.show_polls or not e.poll]
        lines = [_line(e) for e in shown[-MAX_LINES_PER_FLUSH:]]
        if len(shown) > MAX_LINES_PER_FLUSH:
            skipped = len(shown) - MAX_LINES_PER_FLUSH
            stamp = shown[-MAX_LINES_PER_FLUSH - 1]
            when = stamp.time if isinstance(stamp, Frame) else stamp[0]
            lines.insert(
                0,
                f"{clock_text(when)} ── {skipped} earlier lines not drawn (faster than anyone "
                "reads): --record FILE keeps every frame ──",
            )
        if lines:
            # Log follows only when the view already sat at the end, and any layout
            # change (a resize, the candidate list) moves the end away from the view:
            # follow by this widget's own flag instead, until F4 freezes it.
            self.write_lines(lines, scroll_end=False)
            if self.auto_scroll:
                self.scroll_end(animate=False, immediate=True, x_axis=False)
        return len(events)

    def _update_size(self, updates: int, lines: list[str]) -> None:  # type: ignore[override]
        """Log's width update, done here and now: Log starts a thread per write for it
        (cell widths of every line). Frame lines are ASCII but for the arrows, so their
        length is their width; only another line is measured. Also safe at shutdown."""
        if not lines:
            return
        width = max(
            len(line) if line.isascii() or _NARROW.issuperset(line) else cell_len(line)
            for line in lines
        )
        self._update_maximum_width(updates, width)


#: Characters of a frame line that are one cell wide though not ASCII.
_NARROW = frozenset("→←↵─ ·") | frozenset(chr(c) for c in range(32, 127))


def _line(event: Frame | tuple[float, str]) -> str:
    if isinstance(event, Frame):
        return frame_line(event)
    stamp, text = event
    return f"{clock_text(stamp)} ── {terminal_safe(text)} ──"
