"""The engine's CSV log: waiting for rows to log, logging, or stopped by a failure.

Owned by the engine's thread, like everything the engine holds. In a cell the log is
the cell's (:class:`~.cellcsv.CellCsv`, one file for every target): the sink then hands
it this target's cycles under the target's name, and starting or stopping it from any
target starts or stops it for all.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable

from ...commands.language import VarRef
from ...protocol import InputError
from .cellcsv import CellCsv, good_values
from .csvlog import CsvLog, open_for_append
from .rows import WatchRow


class CsvSink:
    """At most one :class:`CsvLog`; a path given with nothing watched waits (``pending``)
    for the first cycle with rows, whose variables become its columns. A path starting
    with ``~`` is under the home directory, as for ``save`` and ``load``."""

    def __init__(
        self,
        alert: Callable[[str], None],
        changed: Callable[[], None],
        cell: tuple[CellCsv, str] | None = None,
    ) -> None:
        """``cell``: the cell's log and this target's name in it."""
        self.cell: CellCsv | None = cell[0] if cell is not None else None
        self._name = cell[1] if cell is not None else ""
        self._alert = alert
        self._changed = changed  # the status line must say so
        self.log: CsvLog | None = None
        self.pending: str | None = None
        self._pending_fd: int | None = None  # held open: a pipe's reader sees no end
        self._starting = False  # a log failing as it starts: its starter says so
        #: Why a log failed on its own (a write, or a start at the first cycle); kept
        #: when another log starts, for the exit status.
        self._failure: str | None = None

    @property
    def failure(self) -> str | None:
        return self.cell.failure if self.cell is not None else self._failure

    @property
    def path(self) -> str | None:
        """Where rows go (or will go from the next cycle); None: not logging."""
        if self.cell is not None:
            return self.cell.path
        return self.log.path if self.log is not None else self.pending

    def wait_for_rows(self, path: str) -> None:
        """Log to ``path`` from the first cycle (InputError: it cannot be written)."""
        if self.cell is not None:
            self.cell.wait_for_rows(path)
            self._changed()
            return
        path = os.path.expanduser(path)
        fd = open_for_append(path)
        self._close_pending()
        self.pending, self._pending_fd = path, fd
        self._changed()

    def start(self, path: str, variables: list[VarRef], fd: int | None = None) -> CsvLog:
        """Log ``variables`` to ``path`` from now on (InputError: it cannot). A log
        whose header failed is returned with its ``failure`` set, for the caller to
        tell, and not kept; :attr:`failure` keeps it for the exit status."""
        self._close_pending()
        self._starting = True
        try:
            log = CsvLog(os.path.expanduser(path), variables, self._failed, fd)
        finally:
            self._starting = False
            self._changed()
        if log.failure is None:
            self.log = log
        return log

    def stop(self) -> CsvLog | None:
        """End the log (or the one waiting for its first cycle); the one ended."""
        if self.cell is not None:
            ended = self.cell.stop()
            self._changed()
            return ended
        log, self.log = self.log, None
        self._close_pending()
        if log is not None:
            log.close()
        self._changed()
        return log

    def cycle_ended(self, wall: float, rows: dict[VarRef, WatchRow]) -> None:
        """One row: each column's last good value, empty when its last poll failed."""
        if self.cell is not None:
            self.cell.cycle_ended(self._name, wall, rows)
            return
        if self.pending is not None:
            path, fd = self.pending, self._pending_fd
            self.pending = self._pending_fd = None
            try:
                started = self.start(path, list(rows), fd)
            except InputError as exc:
                self._failure = f"CSV log not started: {exc}"
                self._alert(self._failure)
                self._changed()
                return
            if started.failure is not None:
                self._alert(started.failure)
        log = self.log
        if log is None:
            return
        log.write(wall, good_values(log.variables, rows))

    def close(self) -> None:
        """The engine stops: its own log ends; a cell's is the cell's to close."""
        if self.cell is None:
            self.stop()

    def _close_pending(self) -> None:
        fd, self._pending_fd, self.pending = self._pending_fd, None, None
        if fd is not None:
            with contextlib.suppress(OSError):
                os.close(fd)

    def _failed(self, text: str) -> None:
        self._failure, self.log = text, None
        if not self._starting:
            self._alert(text)
            self._changed()
