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

from collections.abc import Callable
from typing import TYPE_CHECKING, ClassVar

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import BindingType
from textual.containers import Vertical
from textual.message import Message
from textual.widget import Widget
from textual.widgets import Static

from ..present.trends import bar_lines, bin_window, field_labels, number_text, span_text
from . import keys

if TYPE_CHECKING:
    from ..commands.language import VarRef
    from ..present.trends import TrendStore, Window

#: The windows `w` steps through, in seconds (the store reaches back 5 minutes).
WINDOWS = (10.0, 60.0, 300.0)
#: The view's own keys are reached by F6 (``t`` leaves the focus on the table).
SUBTITLE = "Esc closes · F6 here: w window"


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
    """The window's samples binned by time into one column per cell of its width; in a
    cell's overlay, one lane per series, one above the other on the same time axis,
    each named on its left."""

    def __init__(self, **kwargs: str | None) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.window: Window | None = None
        self.scale: tuple[float | None, float | None] = (None, None)
        self.lanes: tuple[Lane, ...] = ()

    def show(self, window: Window, scale: tuple[float | None, float | None]) -> None:
        """Draw ``window`` on ``scale`` (low, high); a no-op when nothing changed."""
        if window != self.window or scale != self.scale or self.lanes:
            self.window, self.scale, self.lanes = window, scale, ()
            self.refresh()

    def show_lanes(self, lanes: tuple[Lane, ...]) -> None:
        """Draw several series, each in a lane of its own (name, window, scale)."""
        if lanes != self.lanes:
            self.window, self.lanes = None, lanes
            self.refresh()

    def lines(self) -> list[str]:
        """The bars as drawn now, the top line first."""
        width, height = self.size
        if self.lanes:
            return lane_lines(self.lanes, width, height)
        window = self.window
        if window is None:
            return []
        return bar_lines(bin_window(window, width), height, *self.scale)

    def render(self) -> Text:
        return Text("\n".join(self.lines()), no_wrap=True, overflow="crop", end="")


#: One series of an overlay: its name as shown, its window, its scale.
Lane = tuple[str, "Window", tuple[float | None, float | None]]


def lane_lines(lanes: tuple[Lane, ...], width: int, height: int) -> list[str]:
    """Lanes one above the other, the height shared out (the first ones get what is
    left over), each line starting with its lane's name in a column of one width, so
    every lane's bars run on the same time axis."""
    if not lanes or height <= 0:
        return []
    names = max(len(name) for name, _, _ in lanes) + 1
    bars = max(1, width - names)
    lines: list[str] = []
    share, extra = divmod(height, len(lanes))
    for n, (name, window, scale) in enumerate(lanes):
        rows = share + (1 if n < extra else 0)
        drawn = bar_lines(bin_window(window, bars), rows, *scale)
        for m, line in enumerate(drawn):
            lines.append(f"{name if m == rows - 1 else '':<{names}}{line}")
    return lines


#: A series of the view: its target (a cell's member), its variable, its label.
Series = tuple[str, "VarRef", str]


class TrendView(Vertical, can_focus=True):
    BINDINGS: ClassVar[list[BindingType]] = keys.TREND_VIEW

    class Closed(Message):
        """The view asks to close (Esc or t)."""

    class FieldCycled(Message):
        """`f` in the view: the row's trend follows its next field."""

        def __init__(self, var: VarRef, target: str = "") -> None:
            super().__init__()
            self.var = var
            self.target = target

    def __init__(self, trends: Callable[[str], TrendStore], **kwargs: object) -> None:
        """``trends(name)``: a target's store (a single target's is named too)."""
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.trends = trends
        #: What is drawn: one series, or (a cell's overlay) several on one time axis.
        self.series: list[Series] = []
        self.fields: list[int] = []
        self.window = WINDOWS[0]
        self.stats = Static(id="trend-stats")
        self.bars = TrendBars(id="trend-spark")
        self._stats = Text()
        self._title = Text()

    @property
    def var(self) -> VarRef | None:
        """The first series' variable (the row ``t`` opened the view on)."""
        return self.series[0][1] if self.series else None

    @property
    def target(self) -> str:
        return self.series[0][0] if self.series else ""

    @property
    def field(self) -> int:
        return self.fields[0] if self.fields else 0

    @field.setter
    def field(self, field: int) -> None:
        if self.fields:
            self.fields[0] = field

    def on_mount(self) -> None:
        self.border_subtitle = SUBTITLE

    def compose(self) -> ComposeResult:
        yield self.stats
        yield self.bars

    def show_row(self, var: VarRef, label: str, field: int, target: str = "") -> None:
        self.series, self.fields = [(target, var, label)], [field]
        self.redraw()

    def add_row(self, var: VarRef, label: str, field: int, target: str) -> bool:
        """Overlay another row (another target's, or the same's); False when shown."""
        if any(t == target and v == var for t, v, _ in self.series):
            return False
        self.series.append((target, var, label))
        self.fields.append(field)
        self.redraw()
        return True

    def shows(self, target: str, var: VarRef) -> bool:
        return any(t == target and v == var for t, v, _ in self.series)

    def forget(self, target: str, var: VarRef) -> bool:
        """An unwatched row leaves the overlay; True when nothing is left to draw."""
        kept = [
            (s, f) for s, f in zip(self.series, self.fields, strict=True) if s[:2] != (target, var)
        ]
        self.series = [s for s, _ in kept]
        self.fields = [f for _, f in kept]
        return not self.series

    def redraw(self) -> None:
        """Take the window from the store again; draw only what changed."""
        if len(self.series) > 1:
            self._redraw_overlay()
            return
        var = self.var
        if var is None:
            return
        labels = field_labels(var.kind)
        title = Text(f"Trend {var}")
        if labels:
            title.append(f" {labels[self.field]}", style="bold")
        label = self.series[0][2]
        if label:
            title.append(f"  {label}", style="dim")  # made terminal-safe by the app
        if title != self._title:
            self._title = title
            self.border_title = title
        window = self.trends(self.target).window(var, self.field, self.window)
        stats = stats_text(window)
        if stats != self._stats:
            self._stats = stats
            self.stats.update(stats)
        io = var.kind.code == "IO"
        self.bars.show(window, (0.0, 1.0) if io else (window.low, window.high))

    def _redraw_overlay(self) -> None:
        """Several series on one time axis: every window ends at the newest cycle of
        any of their targets."""
        names = [
            f"{t} {v}" + (f" {field_labels(v.kind)[f]}" if field_labels(v.kind) else "")
            for (t, v, _), f in zip(self.series, self.fields, strict=True)
        ]
        title = Text("Trend " + " + ".join(names))
        if title != self._title:
            self._title = title
            self.border_title = title
        stores = [self.trends(t) for t, _, _ in self.series]
        ends = [store.latest for store in stores if store.latest is not None]
        end = max(ends) if ends else None
        lanes: list[Lane] = []
        stats = Text(no_wrap=True, overflow="ellipsis")
        for n, (store, (target, var, _), field, name) in enumerate(
            zip(stores, self.series, self.fields, names, strict=True)
        ):
            window = store.window(var, field, self.window, end)
            io = var.kind.code == "IO"
            lanes.append(
                (f"{target} {var}", window, (0.0, 1.0) if io else (window.low, window.high))
            )
            if n:
                stats.append("  ·  ", style="dim")
            stats.append(f"{name} ", style="dim")
            stats.append(number_text(window.last), style="bold")
        stats.append(f"  ·  {window_name(self.window)}", style="dim")
        if stats != self._stats:
            self._stats = stats
            self.stats.update(stats)
        self.bars.show_lanes(tuple(lanes))

    def action_cycle_window(self) -> None:
        self.window = WINDOWS[(WINDOWS.index(self.window) + 1) % len(WINDOWS)]
        self.redraw()

    def action_cycle_field(self) -> None:
        if self.var is not None:
            self.post_message(self.FieldCycled(self.var, self.target))

    def action_close(self) -> None:
        self.post_message(self.Closed())
