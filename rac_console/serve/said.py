"""What ``rac-console serve`` says on its standard error, so that nobody who can connect
can flood it or, through a terminal that does not read, stall the server.

- **One line per kind every 10 s.** A refusal, a malformed request, an accept that ran
  out of files, a session's failure: the first of a kind is said at once; the next ones
  within :data:`WINDOW` seconds are counted, and the window ends with one line, the
  newest of them and how many more came (``… and 1,234 more in the last 10 s``). A
  kind is a fixed name, never text from the request (which would make a kind per
  request).
- **No traceback.** aiohttp's and asyncio's log records and the loop's exception
  handler become one line each, the exception's type and first line escaped.
- **Writes never block the event loop.** Lines go to a bounded buffer that a thread of
  their own writes to file descriptor 2; when the terminal does not read, the thread
  waits, not the server; past :data:`MOST_WAITING` bytes lines are dropped and counted,
  and the count is said once the terminal reads again.

:class:`Tally` is the counting, pure (the time is given); :class:`Said` the buffer and
its thread; :func:`listen` routes the logging and the loop's exceptions to it.
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..protocol.text import terminal_safe

#: Each kind says at most one line in this many seconds.
WINDOW = 10.0

#: How many bytes may wait for the terminal before lines are dropped.
MOST_WAITING = 64 * 1024

#: What every line starts with.
LEAD = "rac-console serve: "


@dataclass
class _Kind:
    since: float  # when the window began
    held: int = 0  # lines held back in it
    newest: str = ""


class Tally:
    """Which lines of which kind are said now, and which are counted for later."""

    def __init__(self, window: float = WINDOW) -> None:
        self.window = window
        self._kinds: dict[str, _Kind] = {}

    def say(self, kind: str, line: str, now: float) -> str | None:
        """``line`` when it is said now, None when it is counted for the window's end."""
        state = self._kinds.get(kind)
        if state is None:
            self._kinds[kind] = _Kind(since=now)
            return line
        state.held += 1
        state.newest = line
        return None

    def due(self, now: float, closing: bool = False) -> list[str]:
        """The lines of the windows that ended by ``now`` (every window when
        ``closing``): the newest line of each and how many more came."""
        lines = []
        for kind, state in list(self._kinds.items()):
            if not closing and now - state.since < self.window:
                continue
            if state.held:
                lines.append(summary(state.newest, state.held - 1, now - state.since))
                state.since, state.held = now, 0
            else:
                del self._kinds[kind]  # a quiet window: the next line is said at once
        return lines

    def next_due(self) -> float | None:
        """When the next window ends (None: no window open)."""
        return min((s.since + self.window for s in self._kinds.values()), default=None)


def summary(newest: str, more: int, seconds: float) -> str:
    if more <= 0:
        return newest
    seconds = max(1, math.ceil(seconds - 0.05))
    return f"{newest} … and {more:,} more in the last {seconds} s"


class Said:
    """Serve's standard error: lines counted by :class:`Tally` and written by a thread of
    their own (see the module's docstring)."""

    def __init__(
        self,
        write: Callable[[bytes], object] | None = None,
        window: float = WINDOW,
        most_waiting: int = MOST_WAITING,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._write = write or _write_stderr
        self._tally = Tally(window)
        self._clock = clock
        self._most = most_waiting
        self._waiting: deque[bytes] = deque()
        self._size = 0
        self._dropped = 0
        self._closing = False
        self._wake = threading.Condition()
        self._thread = threading.Thread(target=self._run, name="serve-stderr", daemon=True)
        self._thread.start()

    def say(self, kind: str, text: str) -> None:
        """One line of ``kind`` (escaped here), said now or counted; never waits."""
        line = LEAD + terminal_safe(text)
        with self._wake:
            said = self._tally.say(kind, line, self._clock())
            if said is not None:  # a line held back wakes nobody: its window's end will
                self._queue(said)
                self._wake.notify()

    def _queue(self, line: str) -> None:
        data = (line + "\n").encode("utf-8", "replace")
        if self._size + len(data) > self._most:
            self._dropped += 1
            return
        self._waiting.append(data)
        self._size += len(data)

    def _run(self) -> None:
        while True:
            with self._wake:
                while True:
                    for line in self._tally.due(self._clock(), closing=self._closing):
                        self._queue(line)
                    if self._waiting or self._closing:
                        break
                    due = self._tally.next_due()
                    self._wake.wait(None if due is None else max(0.05, due - self._clock()))
                if not self._waiting and self._closing:
                    return
                batch = b"".join(self._waiting)
                self._waiting.clear()
                self._size = 0
                dropped, self._dropped = self._dropped, 0
            if dropped:
                note = f"{LEAD}{dropped:,} lines not shown: this standard error was not read\n"
                batch = note.encode() + batch
            try:
                self._write(batch)  # may wait on the terminal: only this thread waits
            except OSError:
                return  # nobody reads any more: nothing left to tell

    def close(self, wait: float = 1.0) -> None:
        """Say what was counted, and wait up to ``wait`` seconds for it to be written
        (a terminal that does not read does not hold the server's exit)."""
        with self._wake:
            self._closing = True
            self._wake.notify()
        self._thread.join(wait)


def _write_stderr(data: bytes) -> None:
    """All of ``data`` on file descriptor 2, past Python's buffers (a thread blocked in a
    buffered stream's write would hold its lock at the interpreter's exit)."""
    view = memoryview(data)
    while view:
        written = os.write(2, view)
        view = view[written:]


# ------------------------------------------------------------------ logs and the loop


class SaidHandler(logging.Handler):
    """Log records as one line each, counted by kind (the logger and its message's
    template, never the values put in it); no traceback."""

    def __init__(self, said: Said) -> None:
        super().__init__(logging.WARNING)
        self.said = said

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = record.getMessage()
        except Exception:  # a record that cannot be formatted is still one line
            text = str(record.msg)
        exc = record.exc_info[1] if record.exc_info else None
        kind, text = _malformed(exc) or (f"{record.name} {record.msg}", text + _exception(exc))
        self.said.say(kind, text.splitlines()[0] if text else record.name)


def _malformed(exc: BaseException | None) -> tuple[str, str] | None:
    """A request aiohttp could not read: one line naming why."""
    from aiohttp.http_exceptions import HttpProcessingError

    if not isinstance(exc, HttpProcessingError):
        return None
    why = (exc.message or type(exc).__name__).strip().splitlines()
    first = why[0].rstrip(" :") if why else ""
    return "malformed", f"refused a malformed request: {exc.code}, {first}"


def _exception(exc: BaseException | None) -> str:
    if exc is None:
        return ""
    first = str(exc).strip().splitlines()
    return f": {type(exc).__name__}" + (f": {first[0][:200]}" if first else "")


def loop_exceptions(said: Said) -> Callable[[asyncio.AbstractEventLoop, dict[str, Any]], None]:
    """The loop's exception handler: one line a kind, no traceback. Out of file
    descriptors (``ulimit -n``), the loop stops accepting for a second and says so."""

    def handle(_loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        exc = context.get("exception")
        message = str(context.get("message") or "error in the event loop")
        if isinstance(exc, OSError) and "accept" in message:
            reason = exc.strerror or str(exc)
            said.say("accept", f"cannot accept a connection: {reason} (tried again in 1 s)")
            return
        said.say(f"loop {message}", message + _exception(exc))

    return handle


def listen(said: Said, loop: asyncio.AbstractEventLoop) -> Callable[[], None]:
    """Route the log records (aiohttp's, asyncio's, textual-serve's, ours) and the loop's
    exceptions to ``said``; the undoing of it."""
    root = logging.getLogger()
    handler = SaidHandler(said)
    old_level, old_handlers = root.level, root.handlers[:]
    root.handlers[:] = [handler]
    root.setLevel(logging.WARNING)
    loop.set_exception_handler(loop_exceptions(said))

    def undo() -> None:
        root.handlers[:] = old_handlers
        root.setLevel(old_level)
        loop.set_exception_handler(None)

    return undo
