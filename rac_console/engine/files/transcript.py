"""``--log FILE``: a plain-text transcript of the wire, one line per frame, as tio writes.

::

    [2026-11-22 03:45:55.123] TX GET:RC8:10:I:
    [2026-11-22 03:45:55.124] RX 0,3,123
    [2026-11-22 03:45:57.130] -- connection lost: the controller closed the connection

Local time with milliseconds; ``TX`` sent, ``RX`` received, ``--`` a note (a frame cut
off or nobody asked for, the connection lost or back). A frame's CR is left out and
every byte that is not printable ASCII is escaped (``\\x1b``; a backslash is doubled),
so the file has one line per frame whatever the controller sent, and ``grep`` and
``less`` show it as it is. Appended, never truncated, created owner-only, one unbuffered
write per line; a failing disk stops it, said once (:class:`~.recorder.LineFile`).

In a cell, one transcript holds every target's frames, each line naming its target
after the stamp: ``[2026-11-22 03:45:55.123] cell3 TX GET:RC8:10:I:``.
"""

from __future__ import annotations

import time
from functools import lru_cache

from ...protocol import escape_bytes
from ...protocol.text import terminal_safe
from ...session import Frame
from .recorder import LineFile

DIRECTIONS = {"tx": "TX", "rx": "RX"}


@lru_cache(maxsize=4)
def _second_text(second: int) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(second))


def stamp_text(timestamp: float) -> str:
    """``[2026-11-22 03:45:55.123] ``: tio's log prefix, local time with milliseconds."""
    return f"[{_second_text(int(timestamp))}.{int(timestamp % 1 * 1000):03d}] "


class FrameTranscript(LineFile):
    """A frame observer writing the transcript; :meth:`note` adds a ``--`` line."""

    what = "log file"
    stopped = "the --log transcript stopped"

    def __call__(self, frame: Frame, target: str | None = None) -> None:
        if self._fd is None:
            return
        stamp = stamp_text(frame.time) + _named(target)
        complete = frame.data.endswith(b"\r")
        text = escape_bytes(frame.data[:-1] if complete else frame.data)
        asked = f"   [{terminal_safe(frame.source)}]" if frame.source is not None else ""
        lines = [f"{stamp}{DIRECTIONS[frame.direction]} {text}{asked}\n"]
        if frame.unsolicited:
            lines.append(f"{stamp}-- the line above came with no request waiting\n")
        if not complete:
            lines.append(f"{stamp}-- the line above has no CR: the connection closed\n")
        if frame.problem is not None:
            lines.append(f"{stamp}-- the line above was refused: {_one_line(frame.problem)}\n")
        with self.lock:  # a frame's lines together, whichever target writes next
            for line in lines:
                self.append(line.encode("utf-8"))

    def note(self, text: str, when: float | None = None, target: str | None = None) -> None:
        """Our own line (the connection lost, back, a request with no reply)."""
        if self._fd is not None:
            stamp = stamp_text(time.time() if when is None else when) + _named(target)
            self.append(f"{stamp}-- {_one_line(text)}\n".encode())


def _named(target: str | None) -> str:
    """``cell3 `` in a cell's transcript (escaped: an address is typed text); else ''."""
    return "" if target is None else f"{terminal_safe(target).replace(' ', '_')} "


def _one_line(text: str) -> str:
    """Our text, which may quote a reply or a host: controls escaped, one line."""
    return terminal_safe(text)
