"""``--record FILE``: every frame that crossed the wire, one JSON line each.

Each line is written and flushed as the frame is seen, so nothing is lost when a
log scrolls away or the program dies. The file is created owner-only: it may
hold values from a production cell.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import threading
from collections.abc import Callable
from typing import TextIO

from ...protocol import InputError, escape_bytes
from ...session import Frame


def append_whole(fd: int, data: bytes) -> None:
    """One unbuffered write of a whole line; a short one (a disk filled up mid-line) is
    cut back where the file can be, and raised as ENOSPC: a file keeps whole lines."""
    written = os.write(fd, data)
    if written != len(data):
        with contextlib.suppress(OSError):  # a pipe cannot be cut: its reader sees it
            os.ftruncate(fd, os.lseek(fd, 0, os.SEEK_END) - written)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def open_private(path: str, mode: str = "a") -> TextIO:
    """Open a text file to append (``"a"``) or rewrite (``"w"``), created owner-only."""
    flags = os.O_WRONLY | os.O_CREAT | (os.O_TRUNC if mode == "w" else os.O_APPEND)
    fd = os.open(path, flags, 0o600)
    return os.fdopen(fd, mode, encoding="utf-8")  # type: ignore[return-value]


class LineFile:
    """A file appended one whole line at a time, created owner-only.

    A write that fails (a full disk, a quota, a file-size limit) stops the file for
    good: the failure is kept in :attr:`failure` and told once to ``on_failure``; every
    later line is skipped, so the work on screen goes on untouched. Each line is one
    unbuffered write, so the file holds only whole lines up to the failure.

    A cell's engines share one file, each on its own thread: :attr:`lock` is held for
    each write and for the close, so no line is written to a descriptor closed (and
    perhaps reused) by another thread, and a frame's lines stay together.
    """

    #: What the file is, in messages: ``cannot write the {what} FILE``.
    what = "file"
    #: ``{stopped}: No space left on device after 360 {unit}s (FILE)``.
    stopped = "writing stopped"
    unit = "line"

    def __init__(self, path: str, on_failure: Callable[[str], None] | None = None) -> None:
        """Raises InputError when the file cannot be opened for appending."""
        self.path = path
        self.written = 0
        self.failure: str | None = None
        self._on_failure = on_failure
        self.lock = threading.RLock()
        try:
            self._fd: int | None = os.open(
                path, os.O_WRONLY | os.O_CREAT | os.O_APPEND | getattr(os, "O_BINARY", 0), 0o600
            )
        except OSError as exc:
            raise InputError(f"cannot write the {self.what} {path}: {exc.strerror}") from None

    def append(self, line: bytes) -> None:
        """One whole line (its newline included), unless the file stopped."""
        with self.lock:
            if self._fd is None:
                return
            try:
                append_whole(self._fd, line)
            except OSError as exc:
                self._fail(exc)
                return
            self.written += 1

    def _fail(self, exc: OSError) -> None:
        reason = exc.strerror or str(exc)
        count = f"{self.written} {self.unit}{'s' * (self.written != 1)}"
        self.failure = f"{self.stopped}: {reason} after {count} ({self.path})"
        self.close()
        if self._on_failure is not None:
            self._on_failure(self.failure)

    def close(self) -> None:
        with self.lock:
            if self._fd is not None:
                fd, self._fd = self._fd, None
                with contextlib.suppress(OSError):
                    os.close(fd)


class FrameRecorder(LineFile):
    """A frame observer appending JSON lines: ``t``, ``dir``, ``text``, ``rtt_ms``
    (``partial``, ``unsolicited``, and ``refused`` with why for a reply not taken);
    in a cell also ``target``, the name of the target it crossed to or from, and
    ``member``, its place in the cell (1: the first; a replay serves them in that order; a single
    target's lines have none, as they always had). A failing disk stops it, said once
    (see :class:`LineFile`)."""

    what = "record file"
    stopped = "recording stopped"
    unit = "frame"

    @property
    def frames(self) -> int:
        return self.written

    def __call__(self, frame: Frame, target: str | None = None, place: int | None = None) -> None:
        if self._fd is None:
            return
        data = frame.data[:-1] if frame.data.endswith(b"\r") else frame.data
        record: dict[str, object] = {"t": round(frame.time, 6)}
        if target is not None:
            record["target"] = target
        if place is not None:
            record["member"] = place
        record["dir"] = frame.direction
        if frame.source is not None:  # the agent's log: the client that asked
            record["client"] = frame.source
        record["text"] = escape_bytes(data)
        if frame.rtt is not None:
            record["rtt_ms"] = round(frame.rtt * 1000, 3)
        if not frame.data.endswith(b"\r"):
            record["partial"] = True
        if frame.unsolicited:
            record["unsolicited"] = True
        if frame.problem is not None:
            record["refused"] = frame.problem  # a reply the session would not take
        self.append((json.dumps(record) + "\n").encode("ascii"))
