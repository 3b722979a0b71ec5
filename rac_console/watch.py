"""The watch list: which variables are polled, their last values and their health."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from .commands.language import VarRef
from .protocol import Variant

OK = "OK"
WAITING = "…"


@dataclass
class WatchRow:
    var: VarRef
    label: str = ""
    variant: Variant | None = None
    status: str = WAITING
    stale: bool = False
    changed_at: float | None = None
    polled_at: float | None = None
    every: float | None = None  # this row's own poll period; None: the console's interval

    def due(self, now: float, interval: float) -> bool:
        """True when this row should be polled in the cycle starting ``now``."""
        period = self.every if self.every is not None else interval
        # A cycle may start a little early: a row is due within 5 % of its period.
        return self.polled_at is None or now - self.polled_at >= period * 0.95

    def update(self, variant: Variant, now: float) -> bool:
        """A good value came; True when it differs from the last one."""
        changed = self.variant is not None and variant != self.variant
        if changed or self.variant is None:
            self.changed_at = now
        self.variant = variant
        self.status, self.stale, self.polled_at = OK, False, now
        return changed

    def fail(self, status: str, now: float) -> None:
        """The poll failed: keep the last good value, marked stale."""
        self.status, self.stale, self.polled_at = status, True, now


def age_text(row: WatchRow, now: float) -> str:
    if row.changed_at is None:
        return ""
    age = max(0.0, now - row.changed_at)
    if age < 1:
        return "<1s"
    if age < 60:
        return f"{int(age)}s"
    if age < 3600:
        return f"{int(age // 60)}m{int(age % 60):02d}s"
    return f"{int(age // 3600)}h{int(age % 3600 // 60):02d}m"


@dataclass
class WatchList:
    """Changed by the session's thread, read by the screen's: ``removed`` is guarded."""

    rows: dict[VarRef, WatchRow] = field(default_factory=dict)
    dirty: set[VarRef] = field(default_factory=set)
    removed: set[VarRef] = field(default_factory=set)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def add(
        self,
        variables: tuple[VarRef, ...] | list[VarRef],
        label: str = "",
        every: float | None = None,
    ) -> int:
        added = 0
        for var in variables:
            row = self.rows.get(var)
            if row is None:
                with self._lock:
                    self.rows[var] = WatchRow(var, label, every=every)
                    self.removed.discard(var)
                added += 1
            else:
                row.label = label or row.label
                row.every = every if every is not None else row.every
            self.dirty.add(var)
        return added

    def period(self, interval: float) -> float:
        """How often a poll cycle starts: the shortest period any row asks for."""
        rows = list(self.rows.values())  # one step under the GIL: the engine's thread adds rows
        own = [row.every for row in rows if row.every is not None]
        return min([interval, *own]) if len(own) < len(rows) else min(own, default=interval)

    def remove(self, variables: tuple[VarRef, ...] | list[VarRef]) -> int:
        targets = list(self.rows) if not variables else [v for v in variables if v in self.rows]
        with self._lock:
            for var in targets:
                del self.rows[var]
                self.dirty.discard(var)
                self.removed.add(var)
        return len(targets)

    def mark_all(self, status: str) -> None:
        now = time.monotonic()
        for row in self.rows.values():
            row.fail(status, now)
            self.dirty.add(row.var)

    def take_changes(self) -> tuple[set[VarRef], set[VarRef]]:
        """Rows updated and rows removed since the last call (for a batched redraw)."""
        with self._lock:
            dirty, removed = self.dirty, self.removed
            self.dirty, self.removed = set(), set()
        return dirty, removed
