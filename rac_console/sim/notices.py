"""What the simulator tells its user about events nobody asked for, rate-limited.

A client can make the same event happen thousands of times a second. Each kind of
event gets its first line at once and then at most one summary line per window, so
stderr stays a few lines whatever clients do, and a stderr that nobody reads (a pipe)
never fills and stops the simulator. Pure: the clock and the timer are injected.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections import Counter
from collections.abc import Callable

from ..protocol.text import terminal_safe

PREFIX = "rac-console sim: "
WINDOW = 10.0  # seconds
MAX_TEXT = 300  # characters of one line: an exception's text can hold anything

Schedule = Callable[[float, Callable[[], None]], object]


class Notices:
    """``note(kind, text)``: said at once when its kind was quiet for a window; else
    counted, and said once as ``text (N more in the last 10 s)`` when the window ends."""

    def __init__(
        self,
        emit: Callable[[str], None],
        window: float = WINDOW,
        clock: Callable[[], float] = time.monotonic,
        schedule: Schedule | None = None,
    ) -> None:
        self._emit = emit
        self.window = window
        self._clock = clock
        self._schedule = schedule
        self.counts: Counter[str] = Counter()
        self._window_end: dict[str, float] = {}
        self._held: dict[str, tuple[str, int]] = {}  # kind: (its latest text, times held)

    def note(self, kind: str, text: str) -> None:
        self.counts[kind] += 1
        now = self._clock()
        if now < self._window_end.get(kind, -math.inf):
            _, held = self._held.get(kind, (text, 0))
            self._held[kind] = (text, held + 1)
            return
        self._summarise(kind)  # a window whose timer has not fired yet
        self._say(text)
        self._open_window(kind, now)

    def _open_window(self, kind: str, now: float) -> None:
        self._window_end[kind] = now + self.window
        if self._schedule is not None:
            self._schedule(self.window, lambda: self._window_ended(kind))

    def _window_ended(self, kind: str) -> None:
        if self._summarise(kind):  # still busy: a window more of quiet
            self._open_window(kind, self._clock())

    def _summarise(self, kind: str) -> bool:
        held = self._held.pop(kind, None)
        if held is None:
            return False
        text, count = held
        self._say(f"{text} ({count} more in the last {self.window:g} s)")
        return True

    def _say(self, text: str) -> None:
        if len(text) > MAX_TEXT:
            text = text[: MAX_TEXT - 1] + "…"
        with contextlib.suppress(OSError, ValueError):  # stderr closed: nobody to tell
            self._emit(PREFIX + terminal_safe(text))
