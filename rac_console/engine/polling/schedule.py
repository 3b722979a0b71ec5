"""When the next poll cycle starts (pure: told the clock's readings, no I/O).

Starts are counted from the previous *scheduled* start, so a slow reply does not push
the later ones back. A start that is already late begins at once and the count goes on
from it: missed starts are never made up in a burst. After a failure the next start
waits at least until the retry the backoff chose (:meth:`Schedule.not_before`), so a
controller that is down is not asked in a tight loop; a backoff shorter than the
interval leaves the schedule as it was.
"""

from __future__ import annotations


class Schedule:
    def __init__(self) -> None:
        self.due: float | None = None  # when the next start is due; None: at once

    def start(self, now: float, period: float) -> float:
        """The start of the cycle asked for at ``now``: when it is due, or ``now`` when
        that has passed; the one after it is due ``period`` later."""
        start = now if self.due is None else max(self.due, now)
        self.due = start + period
        return start

    def not_before(self, at: float) -> None:
        """No start before ``at`` (a retry after a failure)."""
        self.due = at if self.due is None else max(self.due, at)

    def restart(self) -> None:
        """The watch list, the interval or the target changed: the next start is now."""
        self.due = None

    def wait(self, now: float) -> float:
        """Seconds from ``now`` until the next start is due (0: now)."""
        return 0.0 if self.due is None else max(0.0, self.due - now)
