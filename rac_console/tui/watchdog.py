"""The console's watchdog: the screen never falls behind its engines in silence.

The screen is brought up to date when an engine wakes it (:mod:`.pacing`); should a
wake or a put-off update be lost, every later wake is lost with it (an outbox wakes its
reader only when it stops being empty), and the screen would go on showing the last
state while the engines poll on. So, every :data:`WATCH_EVERY` seconds, on a repeating
timer (which Textual never drops, unlike a one-shot one):

- a deadline whose timer was lost is made (:meth:`Deadline.check`);
- a screen that has not taken what an engine published :data:`STALL_AFTER` seconds ago
  is brought up to date, and says it was behind (the status line, the frame log);
- an engine whose thread has ended without being stopped is shown as stopped, in red,
  never as ``connected``, whatever its last status said.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .deadline import Deadline
    from .members import Members

#: How often the watchdog looks.
WATCH_EVERY = 0.5
#: What an engine published this long ago and the screen has not taken: a stall.
STALL_AFTER = 2.0


class Watchdog:
    """``check()`` on every tick; ``caught_up(seconds)`` is called after a stall was
    ended, ``engine_stopped(name)`` once for each engine found dead."""

    def __init__(
        self,
        members: Members,
        deadlines: Sequence[Deadline],
        catch_up: Callable[[float], None],
        engine_stopped: Callable[[str], None],
    ) -> None:
        self.members = members
        self.deadlines = deadlines
        self.catch_up = catch_up
        self.engine_stopped = engine_stopped
        self.stalls = 0  # stalls ended, for the soak's figures
        self._said_dead: set[str] = set()

    def check(self) -> None:
        for deadline in self.deadlines:
            deadline.check()
        now = time.monotonic()
        waited = [
            now - since
            for outbox in self.members.cell.outboxes
            if (since := outbox.pending_since) is not None
        ]
        if waited and max(waited) > STALL_AFTER:
            self.stalls += 1
            self.catch_up(max(waited))
        for name, state in self.members.states.items():
            engine = state.member.engine
            if name in self._said_dead or not (engine.ended or engine.died):
                continue
            self._said_dead.add(name)
            if state.status is not None and state.status.connection != "engine stopped":
                state.status = replace(state.status, connection="engine stopped")
            self.engine_stopped(name)
