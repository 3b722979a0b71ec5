"""A cell's CSV log: one file for every target, a column per target and variable.

The columns are ``time``, then each target's, in the cell's order, named after it:
``cell3.IO128``, ``cell3.P10.X``, ``cell4.IO64``. The targets poll on their own threads
and at their own pace, so a row is one poll cycle of one target: it fills that target's
columns and leaves the others empty, as a cell is empty when its value was not read in
that cycle (the CSV log's rule for a failed read). Merging cycles of several
controllers into one row would show values read at different moments as if read
together; an empty cell claims nothing.

The columns are fixed when the log starts: each target's are the variables it watches
at its first poll cycle after the log was asked for, so the log starts once every
target has ended one (until then rows are kept, :data:`EARLY_ROWS` at most). A target
with nothing watched never ends a cycle: the log waits for it, and ``log`` says so.
Everything else is the single log's (:class:`~.csvlog.CsvLog`): formulas neutralised,
controls escaped, appended to only under the same header, a failure said once.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable, Mapping, Sequence

from ...commands.language import VarRef
from ...protocol import InputError, Variant
from ..published.events import OK
from .csvlog import CsvLog, fields_of, open_for_append, timestamp, variable_columns
from .rows import WatchRow

#: Rows kept while the log waits for the first cycle of every target.
EARLY_ROWS = 2000


def good_values(
    variables: Sequence[VarRef], rows: Mapping[VarRef, WatchRow]
) -> dict[VarRef, Variant | None]:
    """Each variable's last good value; None when its last poll failed or is stale."""
    values: dict[VarRef, Variant | None] = {}
    for var in variables:
        row = rows.get(var)
        good = row is not None and row.status == OK and not row.stale
        values[var] = row.variant if good and row is not None else None
    return values


class CellCsv:
    """The cell's one CSV log; each member's :class:`~.csvsink.CsvSink` hands it its
    cycles, from the member's thread (every method takes the lock)."""

    def __init__(self, names: Sequence[str], alert: Callable[[str], None]) -> None:
        self.names = tuple(names)
        self._alert = alert  # said once, by the cell
        self._lock = threading.Lock()
        self.log: CsvLog | None = None
        self.pending: str | None = None
        self._pending_fd: int | None = None
        self._columns: dict[str, list[VarRef]] = {}  # reported, by target
        self._early: list[tuple[str, float, str]] = []  # (target, wall, its fields)
        self._widths: dict[str, int] = {}  # each target's columns, once started
        self._told: list[str] = []  # failures to say once the lock is let go
        self.failure: str | None = None

    @property
    def path(self) -> str | None:
        """Where rows go (or will, once every target has polled); None: not logging.
        Read under the lock: another target's thread may be starting the log, between
        its pending path and its log (a cycle that read None there lost its row)."""
        with self._lock:
            log = self.log
            return log.path if log is not None else self.pending

    def waiting_for(self) -> list[str]:
        """The targets whose first poll cycle the log still waits for."""
        with self._lock:
            if self.pending is None:
                return []
            return [name for name in self.names if name not in self._columns]

    def wait_for_rows(self, path: str) -> None:
        """Log to ``path`` once every target has ended a poll cycle (InputError: it
        cannot be written, or the cell logs already)."""
        path = os.path.expanduser(path)
        fd = open_for_append(path)
        with self._lock:
            running = self.log.path if self.log is not None else self.pending
            if running is not None:
                os.close(fd)
                raise InputError(f"already logging to {running}: log stop first")
            self.pending, self._pending_fd = path, fd
            self._columns, self._early = {}, []

    def stop(self) -> CsvLog | None:
        """End the log (or the one waiting); the one ended, None when none had started."""
        with self._lock:
            log, self.log = self.log, None
            self._close_pending()
        if log is not None:
            log.close()
        return log

    def cycle_ended(self, name: str, wall: float, rows: Mapping[VarRef, WatchRow]) -> None:
        """A poll cycle of ``name`` ended: its row (or, the first since the log was
        asked for, its columns)."""
        with self._lock:
            if self.pending is not None:
                self._columns.setdefault(name, list(rows))
                self._keep(name, wall, rows)
                if len(self._columns) == len(self.names):
                    self._start()
            elif self.log is not None:
                self._write(name, wall, self._fields(name, rows))
            told, self._told = self._told, []
        for text in told:
            self._alert(text)

    def _keep(self, name: str, wall: float, rows: Mapping[VarRef, WatchRow]) -> None:
        if len(self._early) < EARLY_ROWS:
            self._early.append((name, wall, self._fields(name, rows)))

    def _fields(self, name: str, rows: Mapping[VarRef, WatchRow]) -> str:
        variables = self._columns.get(name, [])
        values = good_values(variables, rows)
        return ",".join(",".join(fields_of(var, values[var])) for var in variables)

    def _start(self) -> None:
        """Every target has polled: the header, then the rows kept meanwhile."""
        path, fd = self.pending, self._pending_fd
        assert path is not None
        self.pending = self._pending_fd = None
        header = ["time"]
        for name in self.names:
            columns = variable_columns(self._columns[name], f"{name}.")
            header.extend(columns)
            self._widths[name] = len(columns)
        early, self._early = self._early, []
        try:
            log = CsvLog(path, [], self._failed, fd, header)
        except InputError as exc:
            self._failed(f"CSV log not started: {exc}")
            return
        if log.failure is not None:  # its header: said once, by _failed
            return
        self.log = log
        for name, wall, fields in early:
            self._write(name, wall, fields)

    def _write(self, name: str, wall: float, fields: str) -> None:
        log = self.log
        if log is None:
            return
        cells = [timestamp(wall)]
        for other in self.names:
            width = self._widths[other]
            if width:
                cells.append(fields if other == name else "," * (width - 1))
        log.write_cells(cells)

    def _failed(self, text: str) -> None:
        """The log failed (under the lock): it stops for every target, said once."""
        self.failure, self.log = text, None
        self._told.append(text)

    def close(self) -> None:
        """The cell stops: the log ends (its file closed), the one waiting too."""
        self.stop()

    def _close_pending(self) -> None:
        fd, self._pending_fd, self.pending = self._pending_fd, None, None
        self._early = []
        if fd is not None:
            with contextlib.suppress(OSError):
                os.close(fd)
