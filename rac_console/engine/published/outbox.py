"""The one way from the engine's thread to a front end.

The engine puts events; a front end drains them all at once when it is woken (its
``notify``): the console brings its screen up to date, the REPL prints. Row views and
the status replace the ones not yet drained, so a slow reader gets the latest state, not
a backlog.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the console makes its outbox before its first paint, without these
    from ...commands.language import VarRef
    from .events import Event, RowView
    from .status import Status

#: Events kept for a reader that does not drain; past it the oldest frames and cycles go.
MAX_EVENTS = 100_000


@dataclass
class Batch:
    """Everything published since the last drain, in order, plus the latest state."""

    events: list[Event] = field(default_factory=list)
    rows: dict[VarRef, RowView] = field(default_factory=dict)
    removed: set[VarRef] = field(default_factory=set)
    status: Status | None = None
    frames_dropped: int = 0
    cycles_dropped: int = 0  # poll cycles shed (for trends): the reader fell behind

    def apply_rows(self, rows: dict[VarRef, RowView]) -> None:
        """Bring a front end's copy of the watched rows up to date."""
        for var in self.removed:
            rows.pop(var, None)
        rows.update(self.rows)


class Outbox:
    """Thread-safe: ``put*`` from the engine's thread, :meth:`drain` from a front end's.

    ``notify`` (if given) is called on the engine's thread when the outbox stops being
    empty: a front end with an event loop wakes its drain from there. ``lock``: one
    shared by the outboxes of a cell, so that :meth:`drain_together` takes them all at
    one instant.
    """

    def __init__(
        self, notify: Callable[[], None] | None = None, lock: threading.RLock | None = None
    ) -> None:
        self.notify = notify
        #: Reentrant: :meth:`drain_together` holds it while each outbox drains itself.
        self.lock = lock if lock is not None else threading.RLock()
        self._batch = Batch()
        self._empty = True
        #: ``time.monotonic()`` when the outbox stopped being empty, None while it is: a
        #: front end that has not drained for long has stalled (the console's watchdog).
        self.pending_since: float | None = None
        #: ``time.perf_counter()`` when the request in flight left, None when none is; one
        #: writer (the engine's frame observer), read by the status line.
        self.waiting_since: float | None = None

    def put(self, event: Event) -> None:
        with self.lock:
            events = self._batch.events
            events.append(event)
            if len(events) > MAX_EVENTS:
                self._shed_frames()
            woke = self._wake()
        if woke:
            self._notify()

    def put_many(self, events: list[Event], rows: dict[VarRef, RowView] | None = None) -> None:
        """Several events at once, in order, and the row views that follow them: one
        lock for a batch of frames."""
        with self.lock:
            batch = self._batch.events
            batch.extend(events)
            if len(batch) > MAX_EVENTS:
                self._shed_frames()
            if rows:
                self._batch.rows.update(rows)
                self._batch.removed.difference_update(rows)
            woke = self._wake()
        if woke:
            self._notify()

    def put_removed(self, variables: list[VarRef]) -> None:
        with self.lock:
            for var in variables:
                self._batch.rows.pop(var, None)
                self._batch.removed.add(var)
            woke = self._wake()
        if woke:
            self._notify()

    def put_status(self, status: Status) -> None:
        with self.lock:
            self._batch.status = status
            woke = self._wake()
        if woke:
            self._notify()

    def put_dropped(self, frames: int, cycles: int) -> None:
        """Frames and cycles shed before they came here (an agent's client that read
        slowly): counted as if shed here."""
        with self.lock:
            self._batch.frames_dropped += frames
            self._batch.cycles_dropped += cycles
            woke = self._wake()
        if woke:
            self._notify()

    def drain(self) -> Batch:
        with self.lock:
            batch, self._batch = self._batch, Batch()
            self._empty = True
            self.pending_since = None
        return batch

    @staticmethod
    def drain_together(outboxes: Sequence[Outbox]) -> list[Batch]:
        """Drain outboxes that share one lock at one instant: whatever one of them got
        before another got something is in the same drain (a cell's line ended on one
        target, and the next one's answer on another, come out together)."""
        lock = outboxes[0].lock
        if any(outbox.lock is not lock for outbox in outboxes):
            raise ValueError("drain_together needs outboxes made with one lock")
        with lock:
            return [outbox.drain() for outbox in outboxes]

    def _wake(self) -> bool:
        woke, self._empty = self._empty, False
        if woke:
            self.pending_since = time.monotonic()
        return woke

    def _notify(self) -> None:
        notify = self.notify
        if notify is not None:
            with contextlib.suppress(RuntimeError):  # the reader's loop closed: nobody to wake
                notify()

    def _shed_frames(self) -> None:
        """Drop the oldest half of the frames and of the cycles (never a result, note or
        alert): a reader that stopped draining costs a bounded queue, not all memory."""
        from ...session import Frame
        from .events import Cycle

        batch = self._batch
        events = batch.events
        frames = sum(1 for event in events if isinstance(event, Frame))
        cycles = sum(1 for event in events if isinstance(event, Cycle))
        shed_frames, shed_cycles = frames // 2, cycles // 2
        kept: list[Event] = []
        for event in events:
            if shed_frames and isinstance(event, Frame):
                shed_frames -= 1
                batch.frames_dropped += 1
            elif shed_cycles and isinstance(event, Cycle):
                shed_cycles -= 1
                batch.cycles_dropped += 1
            else:
                kept.append(event)
        batch.events = kept
