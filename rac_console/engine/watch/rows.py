"""The watch list: which variables are polled, their last values and their health.

Owned by the engine's thread; front ends see each row as a :class:`RowView`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property

from ...commands.language import VarRef
from ...protocol import Variant
from ...protocol.request import Request, get_for
from ..published.events import OK, WAITING, RowView


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
    watched: bool = True  # False once unwatched (a poll cycle may still hold the row)
    quiet: bool = False  # the next value is the first from a new target: no change

    @cached_property
    def request(self) -> Request:
        """The GET this row is polled with, made once: the one request the poller sends,
        and so checked here to be a well-formed GET (once per row, never per poll)."""
        request = get_for(self.var.kind, self.var.index)
        if not request.read_only_safe:  # a row reads: it never hands the session a write
            raise AssertionError(f"a watched row's request must be a GET: {request.text!r}")
        return request

    def due(self, now: float, interval: float) -> bool:
        """True when this row should be polled in the cycle starting ``now``."""
        period = self.every if self.every is not None else interval
        # A cycle may start a little early: a row is due within 5 % of its period.
        return self.polled_at is None or now - self.polled_at >= period * 0.95

    def update(self, variant: Variant, now: float) -> bool:
        """A good value came; True when what a table shows changed."""
        same = variant is self.variant or variant == self.variant  # a repeated reply: the same
        shown_changed = self.status != OK or not same
        if not same and not self.quiet:
            self.changed_at = now
        self.quiet = False
        self.variant = variant
        self.status, self.stale, self.polled_at = OK, False, now
        return shown_changed

    def fail(self, status: str, now: float) -> bool:
        """The poll failed: keep the last good value, marked stale (a row never read
        has no value to be stale: it shows the failure alone). True when what a table
        shows changed."""
        stale = self.variant is not None
        shown_changed = self.status != status or self.stale != stale
        self.status, self.stale, self.polled_at = status, stale, now
        return shown_changed

    def view(self) -> RowView:
        return RowView(
            self.var,
            self.label,
            self.variant,
            self.status,
            self.stale,
            self.changed_at,
            self.every,
        )


@dataclass
class WatchList:
    rows: dict[VarRef, WatchRow] = field(default_factory=dict)

    def add(
        self,
        variables: tuple[VarRef, ...] | list[VarRef],
        label: str = "",
        every: float | None = None,
    ) -> int:
        """Add rows; a label or ``every`` given again updates a row. How many were new."""
        added = 0
        for var in variables:
            row = self.rows.get(var)
            if row is None:
                self.rows[var] = WatchRow(var, label, every=every)
                added += 1
            else:
                row.label = label or row.label
                row.every = every if every is not None else row.every
        return added

    def period(self, interval: float) -> float:
        """How often a poll cycle starts: the shortest period any row asks for."""
        rows = self.rows.values()
        own = [row.every for row in rows if row.every is not None]
        return min([interval, *own]) if len(own) < len(rows) else min(own, default=interval)

    def remove(self, variables: tuple[VarRef, ...] | list[VarRef]) -> list[VarRef]:
        """Remove these rows (none given: all); the ones that were watched."""
        targets = list(self.rows) if not variables else [v for v in variables if v in self.rows]
        for var in targets:
            self.rows.pop(var).watched = False
        return targets

    def start_afresh(self) -> list[WatchRow]:
        """A new target: every row forgets the old one's value and change, so nothing of
        it is shown as the new one's (its first value is no change either)."""
        for row in self.rows.values():
            row.variant, row.status, row.stale = None, WAITING, False
            row.changed_at, row.polled_at, row.quiet = None, None, True
        return list(self.rows.values())

    def mark_all(self, status: str) -> list[WatchRow]:
        """Every row failed the same way (a lost connection); the rows whose view changed."""
        now = time.monotonic()
        return [row for row in self.rows.values() if row.fail(status, now)]
