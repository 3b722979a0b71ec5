"""Trends of watched values: a bounded store of samples per variable, and sparkline text.

The console feeds it one poll cycle at a time on its own thread, and polling flat out
that is tens of thousands of samples a second, so adding a sample is one deque append:
a sample keeps the reply's value as decoded (a number, a bool, or the list of a P's
fields) and a field is split out only when a series is drawn.

Memory is bounded per variable: the newest :data:`RAW_SAMPLES` samples, every one, and
a long record thinned to one sample per :data:`COARSE_STEP` seconds over
:data:`HORIZON` seconds. A window longer than the raw samples reach is read from the
long record (``Window.thinned``): a spike between two kept samples is not in it.

The trend view draws a window by time, not by sample: :func:`bin_window` cuts it into
one slice per column (``seconds / width`` each), so a window only partly polled shows its
empty part blank instead of stretching what there is over the whole width. Each column
(:func:`bar_lines`) spans the lowest to the highest value polled in its slice, as a
logic analyser draws a signal: an IO bit that stayed ON is a block at the top, one that
stayed OFF a line at the bottom, and one that was both in the slice fills the column, so
neither a short ON nor a short OFF is lost and a fast-toggling bit never reads as steady
(max alone would draw it solid ON, the mean alone would hide a short pulse). A number
is drawn the same way, its column the slice's range. In a one-line view there is no
room for a range: a column is the slice's mean there (a bit's duty cycle).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import islice
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the store reads a cycle; it needs no engine to be tested
    from ..commands.language import VarRef
    from ..engine.published.events import Cycle
    from ..protocol.variables import VarKind

#: Types with a trend: numbers, IO as 0/1, and each field of V P J T (S has none).
TREND_KINDS = frozenset({"I", "F", "D", "IO", "V", "P", "J", "T"})
RAW_SAMPLES = 1024
COARSE_STEP = 0.5
HORIZON = 300.0
BARS = "▁▂▃▄▅▆▇█"
GAP = "·"  # a poll that failed

Sample = tuple[float, Any]  # (time.monotonic(), the reply's value, or None)


def has_trend(kind: VarKind) -> bool:
    return kind.code in TREND_KINDS


def field_labels(kind: VarKind) -> tuple[str, ...]:
    """The fields a row's trend can follow (``X Y Z ...``); empty for a single number."""
    return kind.labels


def field_value(value: Any, field: int) -> float | None:
    """One field of a stored value as a number (IO as 0/1); None for a gap or a value
    that is not a finite number."""
    if value is None:
        return None
    if isinstance(value, list):
        if not 0 <= field < len(value):
            return None
        value = value[field]
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


class _Series:
    __slots__ = ("coarse", "next_coarse", "raw")

    def __init__(self, raw: int, coarse: int) -> None:
        self.raw: deque[Sample] = deque(maxlen=raw)
        self.coarse: deque[Sample] = deque(maxlen=coarse)
        self.next_coarse = -math.inf


@dataclass(frozen=True, slots=True)
class Window:
    """The samples of one field over the last ``seconds`` (oldest first) and their figures."""

    seconds: float
    values: list[float | None]
    low: float | None
    high: float | None
    last: float | None
    thinned: bool  # older than the raw samples reach: one sample per COARSE_STEP
    times: list[float] = field(default_factory=list)  # each value's monotonic() time
    end: float = 0.0  # the window ends here (the newest cycle)
    #: Seconds of the window with data: ``seconds`` when samples reach back before it,
    #: else from its first sample to its end.
    covered: float = 0.0
    #: The value polled just before the window (None: none, or that poll failed): it
    #: holds until the window's first sample.
    before: float | None = None

    @property
    def count(self) -> int:
        return len(self.values)

    @property
    def failed(self) -> int:
        return sum(1 for value in self.values if value is None)


class TrendStore:
    """Samples per watched variable, bounded; read per (variable, field)."""

    def __init__(
        self, raw: int = RAW_SAMPLES, step: float = COARSE_STEP, horizon: float = HORIZON
    ) -> None:
        self._raw = raw
        self._step = step
        self._coarse = max(1, math.ceil(horizon / step))
        self._series: dict[VarRef, _Series] = {}
        #: monotonic() of the newest cycle: windows end there, so a paused screen holds still.
        self.latest: float | None = None

    def add_cycle(self, cycle: Cycle) -> None:
        """Keep one cycle's values: an append per sample, nothing split or converted."""
        t = cycle.monotonic
        series = self._series
        for var, variant in cycle.samples:
            one = series.get(var)
            if one is None:
                if var.kind.code not in TREND_KINDS:
                    continue
                one = series[var] = _Series(self._raw, self._coarse)
            sample = (t, None if variant is None else variant.value)
            one.raw.append(sample)
            if t >= one.next_coarse:
                one.coarse.append(sample)
                one.next_coarse = t + self._step
        self.latest = t

    def clear(self) -> None:
        """Every series goes (a snapshot test stages its own)."""
        self._series.clear()
        self.latest = None

    def forget(self, var: VarRef) -> None:
        """An unwatched variable's samples go (a new watch starts a new trend)."""
        self._series.pop(var, None)

    def __contains__(self, var: object) -> bool:
        return var in self._series

    def last(self, var: VarRef, field: int, count: int) -> list[float | None]:
        """The newest ``count`` samples of a field, oldest first (fewer when fewer came)."""
        one = self._series.get(var)
        if one is None:
            return []
        newest = list(islice(reversed(one.raw), count))
        newest.reverse()
        return [field_value(value, field) for _, value in newest]

    def window(self, var: VarRef, field: int, seconds: float, end: float | None = None) -> Window:
        """The samples of the last ``seconds`` before the newest cycle (or before
        ``end``: a cell's trends of several stores on one time axis), with min/max/last."""
        one = self._series.get(var)
        latest = self.latest if end is None else end
        if one is None or latest is None:
            return Window(seconds, [], None, None, None, False)
        start = latest - seconds
        raw = one.raw
        samples: list[Sample] = []
        prior: Sample | None = None
        for sample in reversed(raw):
            if sample[0] < start:
                prior = sample
                break
            samples.append(sample)
        samples.reverse()
        # Every sample ever kept is in raw while it has not overflowed.
        thinned = len(raw) == raw.maxlen and bool(raw) and raw[0][0] > start
        if thinned:
            first = raw[0][0]
            older = [s for s in one.coarse if start <= s[0] < first]
            samples = older + samples
            prior = next((s for s in reversed(one.coarse) if s[0] < start), None)
        values = [field_value(value, field) for _, value in samples]
        covered = seconds if prior is not None or not samples else latest - samples[0][0]
        numbers = [value for value in values if value is not None]
        last = next((value for value in reversed(values) if value is not None), None)
        return Window(
            seconds,
            values,
            min(numbers) if numbers else None,
            max(numbers) if numbers else None,
            last,
            thinned,
            [t for t, _ in samples],
            latest,
            covered if samples else 0.0,
            None if prior is None else field_value(prior[1], field),
        )


@dataclass(frozen=True, slots=True)
class Bin:
    """The samples of one slice of a window: their range and mean (None when every poll
    in it failed) and how many failed."""

    low: float | None
    high: float | None
    mean: float | None
    failed: int


def bin_window(window: Window, width: int) -> list[Bin | None]:
    """``width`` slices of ``window.seconds / width`` seconds each, the last ending at the
    window's end. A slice with no poll holds the value polled before it (a value is what
    it was last read until the next poll, and slices are often shorter than the poll
    interval); None where nothing was polled yet, or the last poll failed."""
    if width <= 0:
        return []
    step = window.seconds / width
    start = window.end - window.seconds
    groups: list[list[float | None] | None] = [None] * width
    for t, value in zip(window.times, window.values, strict=True):
        n = min(width - 1, max(0, int((t - start) / step)))
        group = groups[n]
        if group is None:
            group = groups[n] = []
        group.append(value)
    bins: list[Bin | None] = []
    held = window.before
    for group in groups:
        if group is None:
            bins.append(None if held is None else Bin(held, held, held, 0))
            continue
        held = group[-1]
        numbers = [value for value in group if value is not None]
        failed = len(group) - len(numbers)
        if numbers:
            bins.append(Bin(min(numbers), max(numbers), math.fsum(numbers) / len(numbers), failed))
        else:
            bins.append(Bin(None, None, None, failed))
    return bins


def bar_lines(
    bins: Sequence[Bin | None], height: int, low: float | None, high: float | None
) -> list[str]:
    """``height`` lines (the top first) drawing each slice as a column from its lowest
    to its highest value on the scale ``low`` to ``high`` (IO: 0 to 1), in eighths of a
    line at the top: blank where nothing was polled, ``·`` at the bottom where every poll
    failed. A flat scale puts everything at mid height; one line draws the mean."""
    if height <= 0:
        return []
    top = len(BARS) * height - 1
    lo = low if low is not None else 0.0
    span = (high if high is not None else lo) - lo

    def level(value: float) -> int:
        if span <= 0:
            return top // 2
        return min(top, max(0, round((value - lo) / span * top)))

    rows = [[" "] * len(bins) for _ in range(height)]  # rows[0] is the bottom
    for column, one in enumerate(bins):
        if one is None:
            continue
        if one.low is None or one.high is None or one.mean is None:
            rows[0][column] = GAP
            continue
        if height == 1:
            rows[0][column] = BARS[level(one.mean)]
            continue
        bottom, peak = level(one.low) // len(BARS), level(one.high)
        for row in range(bottom, peak // len(BARS)):
            rows[row][column] = "█"
        rows[peak // len(BARS)][column] = BARS[peak % len(BARS)]
    return ["".join(row) for row in reversed(rows)]


def span_text(seconds: float) -> str:
    """``4.2 s``, ``93 s``, ``2 min 30 s``: how much of a window has data."""
    if seconds < 10:
        return f"{math.floor(seconds * 10) / 10:g} s"
    whole = round(seconds)
    if whole < 120:  # 93 s reads quicker than 1 min 33 s
        return f"{whole} s"
    minutes, rest = divmod(whole, 60)
    return f"{minutes} min {rest} s" if rest else f"{minutes} min"


def sparkline_text(
    values: Sequence[float | None],
    width: int,
    low: float | None = None,
    high: float | None = None,
) -> str:
    """The newest ``width`` values as bars ``▁▂▃▄▅▆▇█``, right-aligned (the newest at the
    right edge, blanks on the left until there are enough), ``·`` for a failed poll.

    The scale is the values' own min to max unless ``low``/``high`` fix it (IO: 0 to 1);
    a flat series sits at mid height, so it does not read as a minimum.
    """
    shown = list(values[-width:]) if width > 0 else []
    numbers = [value for value in shown if value is not None]
    lo = low if low is not None else min(numbers, default=0.0)
    hi = high if high is not None else max(numbers, default=0.0)
    span = hi - lo
    top = len(BARS) - 1
    bars = []
    for value in shown:
        if value is None:
            bars.append(GAP)
        elif span <= 0:
            bars.append(BARS[top // 2])
        else:
            level = round((value - lo) / span * top)
            bars.append(BARS[min(top, max(0, level))])
    return " " * (width - len(bars)) + "".join(bars)


def number_text(value: float | None) -> str:
    """A figure of a trend: short, as a person reads it (``36.52``, ``1.2e+06``, ``—``)."""
    if value is None:
        return "—"
    if value == int(value) and abs(value) < 1e15:
        return str(int(value))
    return f"{value:.6g}"
