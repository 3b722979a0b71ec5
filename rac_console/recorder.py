"""``--record FILE``: every frame that crossed the wire, one JSON line each.

Each line is written and flushed as the frame is seen, so nothing is lost when a
log scrolls away or the program dies. The file is created owner-only: it may
hold values from a production cell.
"""

from __future__ import annotations

import json
import os
from typing import TextIO

from .client import Frame
from .protocol import InputError, escape_bytes


def open_private(path: str, mode: str = "a") -> TextIO:
    """Open a text file to append (``"a"``) or rewrite (``"w"``), created owner-only."""
    flags = os.O_WRONLY | os.O_CREAT | (os.O_TRUNC if mode == "w" else os.O_APPEND)
    fd = os.open(path, flags, 0o600)
    return os.fdopen(fd, mode, encoding="utf-8")  # type: ignore[return-value]


class FrameRecorder:
    """A frame observer appending JSON lines: ``t``, ``dir``, ``text``, ``rtt_ms``."""

    def __init__(self, path: str) -> None:
        """Raises InputError when the file cannot be opened for appending."""
        self.path = path
        try:
            self._file = open_private(path)
        except OSError as exc:
            raise InputError(f"cannot write the record file {path}: {exc.strerror}") from None

    def __call__(self, frame: Frame) -> None:
        data = frame.data[:-1] if frame.data.endswith(b"\r") else frame.data
        record: dict[str, object] = {
            "t": round(frame.time, 6),
            "dir": frame.direction,
            "text": escape_bytes(data),
        }
        if frame.rtt is not None:
            record["rtt_ms"] = round(frame.rtt * 1000, 3)
        if not frame.data.endswith(b"\r"):
            record["partial"] = True
        if frame.unsolicited:
            record["unsolicited"] = True
        self._file.write(json.dumps(record) + "\n")
        self._file.flush()

    def close(self) -> None:
        self._file.close()
