"""Lines for pipes: each flushed as it is written, and a reader that goes away
(``| head -3``, ``2> >(head -1)``) ends the command quietly rather than in a traceback."""

from __future__ import annotations

import contextlib
import errno
import io
import os
import sys
from collections.abc import Iterator
from typing import Any, TextIO, cast

#: How a write to stdout fails once its reader has gone: EPIPE (BrokenPipeError), and
#: on Windows also EINVAL.
_READER_GONE = {errno.EPIPE, *([errno.EINVAL] if sys.platform == "win32" else [])}


def write_line(text: str) -> None:
    """One line on stdout, flushed now, for readers that act line by line."""
    sys.stdout.write(text + "\n")
    sys.stdout.flush()


def reader_gone(exc: OSError, stream: TextIO | None = None) -> bool:
    """True when the reader of ``stream`` (stdout by default) has gone; the stream then
    points at the null device, so nothing more (Python's last flush at exit included)
    can fail on it."""
    if exc.errno not in _READER_GONE:
        return False
    with contextlib.suppress(OSError, ValueError):  # ValueError: the stream has no descriptor
        null = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, (stream or sys.stdout).fileno())
        finally:
            os.close(null)
    return True


class _Stderr:
    """stderr for a live run, as Rich and ``print`` see it: the real one until its reader
    goes (``2> >(head -1)``), then the null device, and the run goes on with stdout.

    Rich would instead end the process with status 1 (and point stdout at the null
    device too); stdout's lines and the status the run earned matter more than its
    messages. With no stderr at all (None), what is written goes nowhere.
    """

    def __init__(self, real: TextIO | None) -> None:
        self._real = real

    def __getattr__(self, name: str) -> Any:  # encoding, fileno, errors...: the real one's
        if self._real is None:
            raise AttributeError(name)
        return getattr(self._real, name)

    def isatty(self) -> bool:
        return self._real is not None and self._real.isatty()

    def write(self, text: str) -> int:
        with self._unless_gone() as real:
            real.write(text)
        return len(text)

    def flush(self) -> None:
        with self._unless_gone() as real:
            real.flush()

    @contextlib.contextmanager
    def _unless_gone(self) -> Iterator[TextIO]:
        real = self._real if self._real is not None else io.StringIO()
        try:
            yield real
        except OSError as exc:
            if not reader_gone(exc, real):
                raise


@contextlib.contextmanager
def stderr_may_close() -> Iterator[None]:
    """Run with stderr as :class:`_Stderr` (as a decorator: the whole command)."""
    with contextlib.redirect_stderr(cast(TextIO, _Stderr(sys.stderr))):
        yield
