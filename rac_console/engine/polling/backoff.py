"""When the poller may try the controller again (pure: no clock, no I/O).

Reconnecting at once after every failure turns a controller that accepts and then
drops each connection into a storm (50 watched rows: 100 connections a second).
The delay starts at 0.5 s and doubles to 5 s, both when connecting fails and when a
connection closes (whoever closed it, however it was noticed) before it served a couple
of exchanges; a stretch of good exchanges brings it back to the start. A flaky
controller that answers between its faults is not slowed down.
"""

from __future__ import annotations

from dataclasses import dataclass

FIRST_DELAY = 0.5
MAX_DELAY = 5.0
#: A connection closed before it served this many good exchanges was dropped early.
EARLY_EXCHANGES = 2
#: This many good exchanges in a row, and the next failure starts from FIRST_DELAY.
GOOD_STRETCH = 5


@dataclass
class Backoff:
    delay: float = FIRST_DELAY
    served: int = 0  # good exchanges on the current (or the last) connection
    streak: int = 0  # good exchanges in a row, across connections
    is_open: bool = False

    def connected(self) -> None:
        self.is_open, self.served = True, 0

    def good(self) -> None:
        self.served += 1
        self.streak += 1
        if self.streak >= GOOD_STRETCH:
            self.delay = FIRST_DELAY

    def closed(self) -> bool:
        """The connection closed: True when it served too little to be trusted yet,
        and the next try should wait."""
        if not self.is_open:
            return False
        self.is_open = False
        if self.served >= EARLY_EXCHANGES:
            return False
        self.streak = 0
        return True

    def next_delay(self) -> float:
        """The wait before the next try; each call doubles the one after, up to MAX_DELAY."""
        delay = self.delay
        self.delay = min(self.delay * 2, MAX_DELAY)
        self.streak = 0
        return delay
