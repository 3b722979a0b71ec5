"""When the console brings its screen up to date: at each wake of the engines, but
under a flood no more often than the keys can still be answered, and on a clock only
while something on screen changes with time alone.

An update put off is a :class:`~.deadline.Deadline`: its one-shot timer may be lost
(see there), so the clock runs while one is due and makes it when it is overdue; the
app's watchdog is the last resort (:meth:`Pacing.catch_up`).
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING

from .deadline import Deadline

if TYPE_CHECKING:
    from textual.message_pump import MessagePump
    from textual.timer import Timer

#: Under a flood of frames the screen is brought up to date at most this often; the
#: drains in between are put off (a deadline), so keys are answered meanwhile.
MIN_DRAIN_GAP = 1 / 30
#: Under a flood (updates back to back), the costly parts wait their turn: the log is
#: written at most this often, and the table's rows rebuilt at most this often, so
#: the keys typed meanwhile are answered (the repaint budget). The last state always
#: shows: an update put off is made when its turn comes.
LOG_EVERY_UNDER_FLOOD = 1 / 10
TABLE_EVERY_UNDER_FLOOD = 1 / 5
#: The clock's tick: what changes with time alone (row ages, the retry countdown, how
#: long a reply or a line has been waited for, the frame rate) is shown in tenths.
CLOCK_EVERY = 0.2
#: The frame rate on the status line counts the frames drawn in this many seconds.
RATE_WINDOW = 2.0


class Pacing:
    """The wakes and the clock of one screen: ``update(log, table)`` is called with
    which of the costly parts have their turn; ``timed()`` says whether anything shown
    changes with time alone."""

    def __init__(
        self,
        owner: MessagePump,
        update: Callable[[bool, bool], None],
        timed: Callable[[], bool],
        refresh: Callable[[], None],
    ) -> None:
        self.owner = owner
        self.update = update
        self.timed = timed
        self.refresh = refresh  # the table and what changes with time
        self._flushes: deque[tuple[float, int]] = deque()  # (when, frames) in RATE_WINDOW
        self._last = 0.0  # time.monotonic() of the last update
        self._log_at = self._table_at = 0.0  # of the last log write and table refresh
        #: The put-off update, under a flood (the app's watchdog checks it too).
        self.due = Deadline(owner, self.now)
        self.clock: Timer | None = None

    def woke(self) -> None:
        """The engines published: up to date now, or, under a flood, once MIN_DRAIN_GAP
        has passed since the last time (one update put off at a time)."""
        if self.due.armed:  # it takes this wake's events too (made now if overdue)
            self.due.check()
            return
        wait = self._last + MIN_DRAIN_GAP - time.monotonic()
        if wait > 0:
            self._put_off(wait)
        else:
            self.now()

    def _put_off(self, wait: float) -> None:
        """The update in ``wait`` seconds; the clock runs until it is made."""
        self.due.arm(wait)
        self.clock_needed()

    def catch_up(self) -> None:
        """Everything on screen now, log and table, whatever turn they had: the
        watchdog found the screen behind what the engines published."""
        self.due.cancel()
        self._last = self._log_at = self._table_at = 0.0
        self.now()

    def now(self) -> None:
        """Everything published, on screen; under a flood the log and the table wait
        their turn (see LOG_EVERY_UNDER_FLOOD). The table is refreshed only with the log:
        a row never shows what the log has not said yet (a reconnect's row before it)."""
        now = time.monotonic()
        flooded = now - self._last < LOG_EVERY_UNDER_FLOOD
        self._last = now
        log_turn = self._log_at + LOG_EVERY_UNDER_FLOOD
        table_turn = self._table_at + TABLE_EVERY_UNDER_FLOOD
        log = not (flooded and now < log_turn)
        table = log and not (flooded and now < table_turn)
        if log:
            self._log_at = now
        self.update(log, table)
        put_off = log_turn - now if not log else table_turn - now if not table else 0.0
        if put_off > 0:
            self._put_off(put_off)

    def start_clock(self) -> None:
        """The one timer: nothing comes from the engine while a reply, a retry or a typed
        line is waited for, or while polling is paused, yet their clocks and the rows'
        ages must go on. Paused when no clock is shown."""
        self.clock = self.owner.set_interval(CLOCK_EVERY, self._tick)

    def _tick(self) -> None:
        if self.due.check():  # its timer was lost: the update is made here
            return
        self.refresh()
        if self.clock is not None and not self.timed() and not self.due.armed:
            self.clock.pause()

    def clock_needed(self) -> None:
        """Something that counts time is shown now (a line running)."""
        if self.clock is not None:
            self.clock.resume()

    def table_refreshed(self) -> None:
        self._table_at = time.monotonic()
        if self.clock is not None and self.timed():
            self.clock.resume()

    def flushed(self, frames: int) -> None:
        """The log drew ``frames`` frames now (the status line's rate)."""
        if frames:
            self._flushes.append((time.monotonic(), frames))

    def frames_per_second(self) -> float:
        """Frames drawn in the last RATE_WINDOW seconds, per second."""
        flushes = self._flushes
        since = time.monotonic() - RATE_WINDOW
        while flushes and flushes[0][0] < since:
            flushes.popleft()
        return sum(count for _, count in flushes) / RATE_WINDOW
