"""``log FILE.csv`` / ``--log-csv FILE``: the watched values, one CSV row per poll cycle.

The columns are ``time`` (ISO 8601, local time with its offset, milliseconds), then one
per field: ``I10``, ``IO128`` (1 or 0), ``P10.X`` … ``P10.Fig``. They are fixed when
logging starts. An existing file is appended to when its header is the same, refused
when not (a UTF-8 byte order mark before it, as Excel writes one, is no difference);
a last line without its line end is ended first. A named pipe is opened only when a
program reads it (never waited for). Each row is one unbuffered write (flushed each
cycle); a write that fails stops the log for good, told once, like ``--record``.

A controller's string is data, never a formula or a terminal command: a text cell (a
string's value, a column name: anything but a number formatted here) has its control
characters escaped as the screen and the transcript show them (``\\x1b``, an LF
``\\x0a``), so each row is one line whatever the controller sent; one starting like a
formula (``=``, ``+``, ``-``, ``@``, TAB, CR) is prefixed with ``'`` and quoted, as OWASP
advises against CSV injection. A number is left as it is: an I of -5 is ``-5``.
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
from decimal import Decimal
from typing import Any

from ...commands.language import VarRef
from ...protocol import InputError, Variant
from ...protocol.text import counted, scalar_text, terminal_safe
from ...protocol.variant import float_text
from ..files.recorder import append_whole

#: Bytes of an existing file read to find its header.
MAX_HEADER = 1 << 20

#: How a cell starts that a spreadsheet takes for a formula (OWASP, CSV injection).
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")

#: A cell holding one of these is quoted, by the csv rules.
_QUOTED = frozenset(',"\r\n')

#: The values written as numbers, as formatted here.
_NUMBERS = (int, float, Decimal)


def text_cell(text: str) -> str:
    """Text that is not a number formatted here, made safe to open and to ``cat``:
    controls escaped (:func:`terminal_safe`, as shown on screen), so no ESC reaches a
    terminal and no CR or LF splits a row; a formula start prefixed with ``'``."""
    safe = terminal_safe(text)
    return "'" + safe if text.startswith(FORMULA_STARTS) else safe


def csv_field(cell: str) -> str:
    """A cell as written: quoted when the csv rules need it, and always when it starts
    with ``'`` (a neutralised formula: OWASP wants it quoted too)."""
    if cell.startswith("'") or not _QUOTED.isdisjoint(cell):
        return '"' + cell.replace('"', '""') + '"'
    return cell


def columns_of(variables: Iterable[VarRef], prefix: str = "") -> list[str]:
    """``time``, then one column per field of each variable, in order; each name a
    :func:`text_cell`, as a value is (a label is text too)."""
    return ["time", *variable_columns(variables, prefix)]


def variable_columns(variables: Iterable[VarRef], prefix: str = "") -> list[str]:
    """One column per field of each variable: ``I10``, ``P10.X``; with ``prefix``
    (a cell's target: ``cell3.``) ``cell3.I10``."""
    names: list[str] = []
    for var in variables:
        labels = var.kind.labels
        if labels:
            names.extend(text_cell(f"{prefix}{var}.{label}") for label in labels)
        else:
            names.append(text_cell(f"{prefix}{var}"))
    return names


def fields_of(var: VarRef, variant: Variant | None) -> list[str]:
    """A variable's fields as written: empty when its value is unknown or its last
    poll failed; each value a :func:`value_field`."""
    width = len(var.kind.labels) or 1
    if variant is None:
        return [""] * width
    value = variant.value
    if var.kind.labels:
        if isinstance(value, list) and len(value) == width:
            return [value_field(v) for v in value]
        return [""] * width
    if var.kind.code == "IO":
        return ["1" if value else "0"]
    return [value_field(value)]


def value_field(value: Any) -> str:
    """A number as :func:`scalar_text` formats it (-5 stays ``-5``, never quoted);
    anything else, a string above all, is text from the controller: a
    :func:`text_cell`, quoted when it must be (:func:`csv_field`)."""
    if type(value) is float:  # the fields of P, J, T, V: most of a row
        return float_text(value)
    if isinstance(value, _NUMBERS):  # bool too: true, false
        return scalar_text(value)
    return csv_field(text_cell(value if isinstance(value, str) else scalar_text(value)))


def timestamp(wall: float) -> str:
    """``2026-11-22T01:40:00.123+00:00``: local time, its offset, milliseconds."""
    return datetime.fromtimestamp(wall).astimezone().isoformat(timespec="milliseconds")


def open_for_append(path: str) -> int:
    """The log file opened to append to, created owner-only when missing (InputError:
    it cannot be). A named pipe with no program reading it is refused, not waited for."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | getattr(os, "O_BINARY", 0)
    try:
        fifo = stat.S_ISFIFO(os.stat(path).st_mode)
    except OSError:
        fifo = False
    if fifo:  # a blocking open would wait, the engine with it, until a reader comes
        flags |= getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags, 0o600)
    except OSError as exc:
        if fifo and exc.errno == errno.ENXIO:
            raise InputError(
                f"no program is reading the pipe {path}: start the reader first"
            ) from None
        raise InputError(f"cannot write the CSV log {path}: {exc.strerror}") from None
    if fifo and hasattr(os, "set_blocking"):
        os.set_blocking(fd, True)  # each row whole, as the reader takes them
    return fd


def _existing(path: str) -> tuple[list[str] | None, bytes]:
    """The first row of a file that has one (None for a missing or empty file, and for
    a device or a pipe: another program reading the rows as they come), and its last
    byte. A UTF-8 byte order mark before the header is not part of it."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None, b""
        with open(path, "rb") as handle:
            first = handle.readline(MAX_HEADER)
            size = handle.seek(0, os.SEEK_END)
            handle.seek(max(0, size - 1))
            last = handle.read(1)
    except FileNotFoundError:
        return None, b""
    except OSError as exc:
        raise InputError(f"cannot read the CSV log {path}: {exc.strerror}") from None
    text = first.decode("utf-8", "replace").removeprefix("\ufeff")
    line = io.StringIO(text, newline="").readline()  # up to a CR, an LF or both
    if not line:  # empty, or a byte order mark alone: the header still to write
        return None, last
    try:
        return next(csv.reader([line]), []), last
    except csv.Error:  # not CSV at all: one odd column, refused
        return [line.rstrip("\r\n")], last


class CsvLog:
    """One log file with fixed columns; :meth:`write` adds a row."""

    def __init__(
        self,
        path: str,
        variables: list[VarRef],
        on_failure: Callable[[str], None] | None = None,
        fd: int | None = None,
        header: list[str] | None = None,
    ) -> None:
        """Raises InputError when the file cannot be opened, or holds other columns.

        ``fd``: the file opened already (:func:`open_for_append`), now this log's. A
        write that fails, the header's too, sets :attr:`failure` and calls
        ``on_failure`` with it. ``header``: columns of the caller's (a cell's), whose
        rows it writes with :meth:`write_cells`."""
        self.path = path
        self.variables = variables
        self.rows = 0
        self.failure: str | None = None
        self._on_failure = on_failure
        self._started = False  # a write failing before is the header's: nothing written
        #: Each variable's last value and its fields as written, joined: a value seen
        #: again is not formatted again.
        self._fields: dict[VarRef, tuple[Variant | None, str]] = {}
        header = header if header is not None else columns_of(variables)
        try:
            existing, last = _existing(path)
            if existing is not None and existing != header:
                raise InputError(
                    f"{path} holds other columns: {_difference(existing, header)}: log to a "
                    "new file, or watch the same variables"
                )
            if fd is None:
                fd = open_for_append(path)
        except InputError:
            if fd is not None:
                os.close(fd)
            raise
        self._fd: int | None = fd
        self.appending = existing is not None
        # A header or a row someone cut short of its line end: end that line first.
        if self.appending and last != b"\n":
            self._write(b"\n" if last == b"\r" else b"\r\n")
        if not self.appending and self._fd is not None:
            self._write_line(",".join(csv_field(name) for name in header))
        self._started = True

    def write(self, wall: float, values: dict[VarRef, Variant | None]) -> None:
        """One row: the time, then each column's value (empty: unknown or failed)."""
        if self._fd is None:
            return
        row = [timestamp(wall)]
        fields = self._fields
        for var in self.variables:
            variant = values.get(var)
            kept = fields.get(var)
            if kept is None or kept[0] is not variant:  # a value seen again: no new text
                kept = (variant, ",".join(fields_of(var, variant)))
                fields[var] = kept
            row.append(kept[1])
        if self._write_line(",".join(row)):
            self.rows += 1

    def write_cells(self, cells: list[str]) -> None:
        """One row made by the caller: each cell written already (escaped, quoted)."""
        if self._write_line(",".join(cells)):
            self.rows += 1

    def _write_line(self, line: str) -> bool:
        """One row, its fields joined already; every cell is escaped, so one line."""
        return self._write(f"{line}\r\n".encode("utf-8", "surrogateescape"))

    def _write(self, data: bytes) -> bool:
        fd = self._fd
        if fd is None:
            return False
        try:
            append_whole(fd, data)
        except OSError as exc:
            self._fail(exc)
            return False
        return True

    def _fail(self, exc: OSError) -> None:
        reason = exc.strerror or str(exc)
        if not self._started:
            self.failure = f"CSV log not started: cannot write the CSV log {self.path}: {reason}"
        else:
            self.failure = (
                f"CSV log stopped: {reason} after {counted(self.rows, 'row')} ({self.path})"
            )
        self.close()
        if self._on_failure is not None:
            self._on_failure(self.failure)

    def close(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            with contextlib.suppress(OSError):
                os.close(fd)


def _difference(existing: list[str], header: list[str]) -> str:
    """The first place the file's header and this log's differ, then both from there,
    cut short. The file's cells are quoted with repr: whatever they hold shows."""
    at = next(
        (
            n
            for n, (theirs, ours) in enumerate(zip(existing, header, strict=False))
            if theirs != ours
        ),
        min(len(existing), len(header)),
    )
    if at < min(len(existing), len(header)):
        what = f"column {at + 1} is {_cell(existing[at])}, this log's is {_cell(header[at])}"
    else:
        what = f"it has {counted(len(existing), 'column')}, this log has {len(header)}"
    return (
        f"{what} (from column {at + 1} it has {_columns_text(existing[at:])}; "
        f"this log has {_columns_text(header[at:])})"
    )


def _cell(text: str) -> str:
    return repr(text if len(text) <= 40 else text[:39] + "…")


def _columns_text(columns: list[str], shown: int = 4) -> str:
    if not columns:
        return "none"
    text = ", ".join(_cell(column) for column in columns[:shown])
    more = len(columns) - shown
    return text + (f" and {more} more" if more > 0 else "")
