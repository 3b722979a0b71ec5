"""The trend of one watched row over a window of seconds, in place of the frame log.

It takes the frame log's place while open (same height, any terminal size) rather
than squeezing a third pane into 24 lines; the log keeps collecting and is back on
close. Redrawn with the table, from the app's trend store.

The bars are drawn by time, each column a fixed slice of the window (window / width):
a window only partly polled is blank where it has no data, and the header says how much
has (``5 min  ·  93 s of data  ·  480 samples``). How a slice is drawn (its range, so a
fast-toggling bit is never drawn steady) is in :mod:`rac_console.present.trends`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Vertical
from textual.message import Message
from textual.widget import Widget
from textual.widgets import Static

from ..present.trends import bar_lines, bin_window, field_labels, number_text, span_text
from .pane_keys import pane_bindings

if TYPE_CHECKING:
    from ..commands.language import VarRef
    from ..present.trends import TrendStore, Window

#: The windows `w` steps through, in seconds (the store reaches back 5 minutes).
WINDOWS = (10.0, 60.0, 300.0)


def window_name(seconds: float) -> str:
    return f"{seconds:g} s" if seconds < 60 else f"{seconds / 60:g} min"


def stats_text(window: Window) -> Text:
    """``last 36.5  min 35.1  max 37.9  ·  10 s  ·  48 samples``, with ``·  4.2 s of
    data`` after the window when the samples do not reach back over all of it."""
    text = Text(no_wrap=True, overflow="ellipsis")
    for n, (name, value) in enumerate(
        (("last", window.last), ("min", window.low), ("max", window.high))
    ):
        if n:
            text.append("  ")
        text.append(f"{name} ", style="dim")
        text.append(number_text(value), style="bold")
    text.append(f"  ·  {window_name(window.seconds)}", style="dim")
    if window.covered < window.seconds:
        text.append(f"  ·  {span_text(window.covered)} of data", style="dim")
    text.append(f"  ·  {window.count} samples", style="dim")
    if window.failed:
        text.append(f" ({window.failed} failed)", style="red")
    if window.thinned:
        text.append("  (older ones 1 per 0.5 s)", style="dim")
    return text


class TrendBars(Widget):
    """The window's samples binned by time into one column per cell of its width."""

    def __init__(self, **kwargs: str | None) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.window: Window | None = None
        self.scale: tuple[float | None, float | None] = (None, None)

    def show(self, window: Window, scale: tuple[float | None, float | None]) -> None:
        """Draw ``window`` on ``scale`` (low, high); a no-op when nothing changed."""
        if window != self.window or scale != self.scale:
            self.window, self.scale = window, scale
            self.refresh()

    def lines(self) -> list[str]:
        """The bars as drawn now, the top line first."""
        window = self.window
        if window is None:
            return []
        width, height = self.size
        return bar_lines(bin_window(window, width), height, *self.scale)

    def render(self) -> Text:
        return Text("\n".join(self.lines()), no_wrap=True, overflow="crop", end="")


class TrendView(Vertical, can_focus=True):
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("w", "cycle_window", "Window", id="trend-window"),
        Binding("f", "cycle_field", "Trend field", id="trend-field"),
        Binding("t", "close", "Close trend", id="trend-close"),
        Binding("escape", "close", "Close trend", show=False, id="trend-escape"),
        *pane_bindings("trend"),
    ]

    class Closed(Message):
        """The view asks to close (Esc or t)."""

    class FieldCycled(Message):
        """`f` in the view: the row's trend follows its next field."""

        def __init__(self, var: VarRef) -> None:
            super().__init__()
            self.var = var

    def __init__(self, trends: TrendStore, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.trends = trends
        self.var: VarRef | None = None
        self.label = ""
        self.field = 0
        self.window = WINDOWS[0]
        self.stats = Static(id="trend-stats")
        self.bars = TrendBars(id="trend-spark")
        self._stats = Text()
        self._title = Text()

    def compose(self) -> ComposeResult:
        yield self.stats
        yield self.bars

    def show_row(self, var: VarRef, label: str, field: int) -> None:
        self.var, self.label, self.field = var, label, field
        self.redraw()

    def redraw(self) -> None:
        """Take the window from the store again; draw only what changed."""
        var = self.var
        if var is None:
            return
        labels = field_labels(var.kind)
        title = Text(f"Trend {var}")
        if labels:
            title.append(f" {labels[self.field]}", style="bold")
        if self.label:
            title.append(f"  {self.label}", style="dim")  # made terminal-safe by the app
        if title != self._title:
            self._title = title
            self.border_title = title
        window = self.trends.window(var, self.field, self.window)
        stats = stats_text(window)
        if stats != self._stats:
            self._stats = stats
            self.stats.update(stats)
        io = var.kind.code == "IO"
        self.bars.show(window, (0.0, 1.0) if io else (window.low, window.high))

    def action_cycle_window(self) -> None:
        self.window = WINDOWS[(WINDOWS.index(self.window) + 1) % len(WINDOWS)]
        self.redraw()

    def action_cycle_field(self) -> None:
        if self.var is not None:
            self.post_message(self.FieldCycled(self.var))

    def action_close(self) -> None:
        self.post_message(self.Closed())
