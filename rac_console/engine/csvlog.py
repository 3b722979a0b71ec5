"""``log FILE.csv`` / ``--log-csv FILE``: the watched values, one CSV row per poll cycle.

The columns are ``time`` (ISO 8601, local time with its offset, milliseconds), then one
per field: ``I10``, ``IO128`` (1 or 0), ``P10.X`` … ``P10.Fig``. They are fixed when
logging starts. An existing file is appended to when its header is the same, refused
when not. Each row is one unbuffered write (flushed each cycle); a write that fails
stops the log for good, told once, like ``--record``.
"""

from __future__ import annotations

import contextlib
import csv
import errno
import io
import os
import stat
from collections.abc import Callable, Iterable
from datetime import datetime

from ..commands.language import VarRef
from ..protocol import InputError, Variant
from ..protocol.text import scalar_text

#: Bytes of an existing file read to find its header.
MAX_HEADER = 1 << 20


def columns_of(variables: Iterable[VarRef]) -> list[str]:
    """``time``, then one column per field of each variable, in order."""
    names = ["time"]
    for var in variables:
        labels = var.kind.labels
        if labels:
            names.extend(f"{var}.{label}" for label in labels)
        else:
            names.append(str(var))
    return names


def cells_of(var: VarRef, variant: Variant | None) -> list[str]:
    """A variable's cells: empty when its value is unknown or its last poll failed."""
    width = len(var.kind.labels) or 1
    if variant is None:
        return [""] * width
    value = variant.value
    if var.kind.labels:
        if isinstance(value, list) and len(value) == width:
            return [scalar_text(v) for v in value]
        return [""] * width
    if var.kind.code == "IO":
        return ["1" if value else "0"]
    return [value if isinstance(value, str) else scalar_text(value)]


def timestamp(wall: float) -> str:
    """``2026-11-22T01:40:00.123+00:00``: local time, its offset, milliseconds."""
    return datetime.fromtimestamp(wall).astimezone().isoformat(timespec="milliseconds")


def check_writable(path: str) -> None:
    """Refuse at start (InputError) a CSV log that could not be written at all."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    except OSError as exc:
        raise InputError(f"cannot write the CSV log {path}: {exc.strerror}") from None
    os.close(fd)


def _existing_header(path: str) -> list[str] | None:
    """The first row of a file that has one; None for a missing or empty file, and
    for a device or a pipe (another program reading the rows as they come)."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        with open(path, encoding="utf-8", newline="", errors="replace") as handle:
            first = handle.readline(MAX_HEADER)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise InputError(f"cannot read the CSV log {path}: {exc.strerror}") from None
    if not first:
        return None
    return next(csv.reader([first]), [])


class CsvLog:
    """One log file with fixed columns; :meth:`write` adds a row."""

    def __init__(
        self,
        path: str,
        variables: list[VarRef],
        on_failure: Callable[[str], None] | None = None,
    ) -> None:
        """Raises InputError when the file cannot be opened, or holds other columns."""
        self.path = path
        self.variables = variables
        self.rows = 0
        self.failure: str | None = None
        self._on_failure = on_failure
        self._buffer = io.StringIO()
        self._writer = csv.writer(self._buffer, lineterminator="\r\n")
        self._cells: dict[VarRef, tuple[Variant | None, list[str]]] = {}
        header = columns_of(variables)
        existing = _existing_header(path)
        if existing is not None and existing != header:
            raise InputError(
                f"{path} holds other columns ({_columns_text(existing)}), not these "
                f"({_columns_text(header)}): log to a new file, or watch the same variables"
            )
        try:
            self._fd: int | None = os.open(
                path, os.O_WRONLY | os.O_CREAT | os.O_APPEND | getattr(os, "O_BINARY", 0), 0o600
            )
        except OSError as exc:
            raise InputError(f"cannot write the CSV log {path}: {exc.strerror}") from None
        self.appending = existing is not None
        if not self.appending:
            self._write_row(header)

    def write(self, wall: float, values: dict[VarRef, Variant | None]) -> None:
        """One row: the time, then each column's value (empty: unknown or failed)."""
        if self._fd is None:
            return
        row = [timestamp(wall)]
        cells = self._cells
        for var in self.variables:
            variant = values.get(var)
            kept = cells.get(var)
            if kept is None or kept[0] is not variant:  # a value seen again: no new text
                kept = (variant, cells_of(var, variant))
                cells[var] = kept
            row.extend(kept[1])
        if self._write_row(row):
            self.rows += 1

    def _write_row(self, row: list[str]) -> bool:
        buffer = self._buffer
        buffer.seek(0)
        buffer.truncate()
        self._writer.writerow(row)
        data = buffer.getvalue().encode("utf-8", "surrogateescape")
        fd = self._fd
        if fd is None:
            return False
        try:
            written = os.write(fd, data)
            if written != len(data):  # a short write: the disk filled up mid-row
                os.ftruncate(fd, os.lseek(fd, 0, os.SEEK_END) - written)
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        except OSError as exc:
            self._fail(exc)
            return False
        return True

    def _fail(self, exc: OSError) -> None:
        reason = exc.strerror or str(exc)
        self.failure = f"CSV log stopped: {reason} after {self.rows} rows ({self.path})"
        self.close()
        if self._on_failure is not None:
            self._on_failure(self.failure)

    def close(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            with contextlib.suppress(OSError):
                os.close(fd)


def _columns_text(columns: list[str]) -> str:
    shown = ", ".join(columns[1:6])
    more = len(columns) - 6
    return shown + (f" and {more} more" if more > 0 else "") if shown else "none"
