"""Trends of watched values: a bounded store of samples per variable, and sparkline text.

The console feeds it one poll cycle at a time on its own thread, and polling flat out
that is tens of thousands of samples a second, so adding a sample is one deque append:
a sample keeps the reply's value as decoded (a number, a bool, or the list of a P's
fields) and a field is split out only when a series is drawn.

Memory is bounded per variable: the newest :data:`RAW_SAMPLES` samples, every one, and
a long record thinned to one sample per :data:`COARSE_STEP` seconds over
:data:`HORIZON` seconds. A window longer than the raw samples reach is read from the
long record (``Window.thinned``): a spike between two kept samples is not in it.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import islice
from typing import TYPE_CHECKING, Any

from ..commands.language import VarRef
from ..protocol.variables import VarKind

if TYPE_CHECKING:  # the store reads a cycle; it needs no engine to be tested
    from ..engine.events import Cycle

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

    def window(self, var: VarRef, field: int, seconds: float) -> Window:
        """The samples of the last ``seconds`` before the newest cycle, with min/max/last."""
        one = self._series.get(var)
        if one is None or self.latest is None:
            return Window(seconds, [], None, None, None, False)
        start = self.latest - seconds
        raw = one.raw
        samples: list[Sample] = []
        for sample in reversed(raw):
            if sample[0] < start:
                break
            samples.append(sample)
        samples.reverse()
        # Every sample ever kept is in raw while it has not overflowed.
        thinned = len(raw) == raw.maxlen and bool(raw) and raw[0][0] > start
        if thinned:
            first = raw[0][0]
            older = [s for s in one.coarse if start <= s[0] < first]
            samples = older + samples
        values = [field_value(value, field) for _, value in samples]
        numbers = [value for value in values if value is not None]
        last = next((value for value in reversed(values) if value is not None), None)
        return Window(
            seconds,
            values,
            min(numbers) if numbers else None,
            max(numbers) if numbers else None,
            last,
            thinned,
        )


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
