"""The engine's CSV log: waiting for rows to log, logging, or stopped by a failure.

Owned by the engine's thread, like everything the engine holds.
"""

from __future__ import annotations

from collections.abc import Callable

from ..commands.language import VarRef
from ..protocol import InputError, Variant
from .csvlog import CsvLog, check_writable
from .events import OK
from .watch import WatchRow


class CsvSink:
    """At most one :class:`CsvLog`; a path given with nothing watched waits (``pending``)
    for the first cycle with rows, whose variables become its columns."""

    def __init__(self, alert: Callable[[str], None], changed: Callable[[], None]) -> None:
        self._alert = alert
        self._changed = changed  # the status line must say so
        self.log: CsvLog | None = None
        self.pending: str | None = None
        self.failure: str | None = None  # why the last log stopped on its own

    @property
    def path(self) -> str | None:
        """Where rows go (or will go from the next cycle); None: not logging."""
        return self.log.path if self.log is not None else self.pending

    def wait_for_rows(self, path: str) -> None:
        """Log to ``path`` from the first cycle (InputError: it cannot be written)."""
        check_writable(path)
        self.pending = path
        self._changed()

    def start(self, path: str, variables: list[VarRef]) -> CsvLog:
        """Log ``variables`` to ``path`` from now on (InputError: it cannot)."""
        self.pending, self.failure = None, None
        self._changed()
        log = CsvLog(path, variables, self._failed)
        if log.failure is None:  # its header may have failed already
            self.log = log
        return log

    def stop(self) -> CsvLog | None:
        """End the log (or the one waiting for its first cycle); the one ended."""
        log, self.log, self.pending = self.log, None, None
        if log is not None:
            log.close()
        self._changed()
        return log

    def cycle_ended(self, wall: float, rows: dict[VarRef, WatchRow]) -> None:
        """One row: each column's last good value, empty when its last poll failed."""
        if self.pending is not None:
            try:
                self.start(self.pending, list(rows))
            except InputError as exc:
                self._alert(f"CSV log not started: {exc}")
        log = self.log
        if log is None:
            return
        values: dict[VarRef, Variant | None] = {}
        for var in log.variables:
            row = rows.get(var)
            good = row is not None and row.status == OK and not row.stale
            values[var] = row.variant if good and row is not None else None
        log.write(wall, values)

    def _failed(self, text: str) -> None:
        self.failure, self.log = text, None
        self._alert(text)
        self._changed()
