"""A call due at a time, that does not depend on Textual's one-shot timer firing.

Textual ends a one-shot timer without calling it when its delay has already passed by
the time the timer's task first reads the clock (``Timer._run`` counts the tick as
skipped, and a ``repeat=0`` timer then ends): a wait of microseconds is lost most of
the time, and a wait of milliseconds whenever another thread holds the GIL across that
moment. A screen that waits on such a timer waits forever. So no timer is armed for
less than :data:`TIMER_FLOOR`, and the timer is only the fast path: whatever ticks
anyway (the console's clock, the app's watchdog) calls :meth:`Deadline.check`, which
makes a call that is overdue.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from textual.message_pump import MessagePump
    from textual.timer import Timer

#: No one-shot timer is armed for a shorter wait: a shorter one is armed for this long.
TIMER_FLOOR = 0.02
#: A call this long past its time is taken as lost with its timer, and made.
LOST_AFTER = 0.05


class Deadline:
    """At most one call due at a time: :meth:`arm`, then it is made once, by its timer
    or by :meth:`check`, whichever comes first; :meth:`cancel` forgets it."""

    def __init__(self, owner: MessagePump, call: Callable[[], None]) -> None:
        self.owner = owner
        self.call = call
        self.at: float | None = None  # time.monotonic() when the call is due
        self._timer: Timer | None = None
        self._armed = 0  # which arming a timer's callback belongs to

    @property
    def armed(self) -> bool:
        return self.at is not None

    def arm(self, wait: float) -> None:
        """The call in ``wait`` seconds (at least TIMER_FLOOR); one already due stays."""
        if self.at is not None:
            return
        wait = max(wait, TIMER_FLOOR)
        self.at = time.monotonic() + wait
        self._armed += 1
        self._timer = self.owner.set_timer(wait, partial(self._fire, self._armed))

    def check(self) -> bool:
        """Make the call if its timer was lost (it is overdue): True when made."""
        if self.at is None or time.monotonic() < self.at + LOST_AFTER:
            return False
        self._fire(self._armed)
        return True

    def cancel(self) -> None:
        self.at = None
        if self._timer is not None:
            self._timer.stop()
            self._timer = None

    def _fire(self, armed: int) -> None:
        if self.at is None or armed != self._armed:
            return  # made already, or forgotten: a late timer of an earlier arming
        self.cancel()
        self.call()
