"""Command history shared by the console and the REPL: one file, bounded, owner-only.

The file holds one command per line (commands never contain a newline), oldest
first. Consecutive duplicates are not stored; the file is trimmed to the newest
``limit`` entries when it grows past twice that.

Several consoles may share the file: each appends, and a trim keeps the newest
lines *of the file* (not of one console's memory), under a lock that appends take
too, so no console's entries are lost and none is written to a file being replaced.

A front end enters a line when it is typed (Up recalls it at once) and settles it
when its result comes: a line refused before anything was sent (a mistyped command,
bad syntax, a write the target's rules refuse) stays for Up in this session, to be
fixed, but is never suggested and never written, so no later session offers it.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the console opens its history before its first paint, without these
    from ..engine.published.events import Result

DEFAULT_LIMIT = 1000


def default_history_path() -> Path:
    from platformdirs import user_state_path

    return user_state_path("rac-console") / "history"


def _distinct(lines: list[str]) -> list[str]:
    """Each line once, at its last use (the file keeps every use: it is appended to)."""
    return list(reversed(dict.fromkeys(reversed(lines))))


class History:
    """The lines typed: recalled, suggested, and appended to ``path`` (None: kept in
    memory only, as a console served to a browser keeps them)."""

    def __init__(self, path: Path | str | None, limit: int = DEFAULT_LIMIT) -> None:
        self.path = Path(path) if path is not None else None
        self.limit = limit
        lines = self._read()
        self.entries: list[str] = _distinct(lines)[-limit:]
        self._pending: list[str] = []  # entered, result not known yet: not on file yet
        self._refused: set[str] = set()  # refused in this session: never suggested
        self._written = lines[-1] if lines else None  # no line is written twice in a row
        # A file left long by an earlier run is trimmed at this run's first append.
        self._appends = limit if len(lines) >= 2 * limit else 0
        with contextlib.suppress(OSError):  # an older file may be readable by others
            if self.path is not None and self.path.exists():
                self.path.chmod(0o600)

    def _read(self) -> list[str]:
        if self.path is None:
            return []
        try:
            text = self.path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            return []
        return [line for line in text.split("\n") if line.strip()]

    def append(self, line: str) -> None:
        """Remember a command now, recalled, suggested and written; blank lines and
        repeats of the last one are skipped."""
        self.enter(line)
        self.settle(line, refused=False)

    def enter(self, line: str) -> None:
        """A line typed, its result not known yet: Up recalls it at once; it is
        written (and suggested) when :meth:`settle` says it was not refused."""
        line = _one_line(line)
        if not line.strip():
            return
        if not (self.entries and self.entries[-1] == line):
            if line in self.entries:  # each line once, where it was last used
                self.entries.remove(line)
            self.entries.append(line)
            del self.entries[: -self.limit]
        self._pending.append(line)

    def settle(self, line: str, *, refused: bool) -> None:
        """The result of an entered line came (lines settle in the order entered): a
        refused one is kept from suggestions and from the file; any other is written.
        A line never entered (made by a key on a row) settles nothing."""
        line = _one_line(line)
        if line not in self._pending:
            return
        self._pending.remove(line)
        if refused:
            self._refused.add(line)
            return
        self._refused.discard(line)  # refused on one target, run on the next
        if line != self._written:
            self._written = line
            self._write(line)

    def suggest(self, text: str) -> str | None:
        """The newest line that starts with ``text`` and is longer (the grey text of
        both front ends), never a line refused in this session."""
        if not text.strip():
            return None
        for entry in reversed(self.entries):
            if entry.startswith(text) and entry != text and entry not in self._refused:
                return entry
        return None

    def _write(self, line: str) -> None:
        from ..engine.files.recorder import open_private

        if self.path is None:
            return
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with _locked(self.path):
                with open_private(str(self.path)) as handle:
                    handle.write(line + "\n")
                self._appends += 1
                if self._appends >= self.limit:  # now and then, see whether to trim
                    self._appends = 0
                    self._trim()
        except OSError:
            pass  # history is a convenience: a read-only home must not stop the console

    def _trim(self) -> None:
        """Keep the newest ``limit`` lines of the file as it is now (the lock is held)."""
        from ..engine.files.recorder import open_private

        assert self.path is not None  # only a file is trimmed
        lines = self._read()
        if len(lines) < 2 * self.limit:
            return
        temporary = self.path.with_name(self.path.name + ".tmp")
        with open_private(str(temporary), "w") as handle:
            handle.write("".join(entry + "\n" for entry in lines[-self.limit :]))
        os.replace(temporary, self.path)


def _one_line(line: str) -> str:
    """A history entry is one line of the file."""
    return line.replace("\r", " ").replace("\n", " ")


def is_refused(result: Result) -> bool:
    """Whether a line was answered with an error before anything was sent: it did not
    parse (a word no command has, bad syntax), or a write the target's rules (or the
    user, at a confirm question) refused. A line that failed for the state it met
    (not connected, a timeout) is right, and kept."""
    from ..commands.outcome import ExitStatus, Outcome
    from ..engine.published.events import Message

    if any(isinstance(f, Outcome) and f.status == ExitStatus.REFUSED for f in result.feedback):
        return True
    return result.command is None and any(
        isinstance(f, Message) and f.level == "error" for f in result.feedback
    )


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """An exclusive lock beside the history file, shared by every console using it:
    ``flock`` on POSIX, ``msvcrt.locking`` on Windows."""
    fd = os.open(str(path.with_name(path.name + ".lock")), os.O_RDWR | os.O_CREAT, 0o600)
    try:
        _lock(fd)
        try:
            yield
        finally:
            _unlock(fd)
    finally:
        os.close(fd)


#: How long an append waits for another console's lock before it gives the line up.
LOCK_TRIES, LOCK_PAUSE = 50, 0.01


def _lock(fd: int) -> None:
    """Take the lock without blocking for long: the screen's thread appends, and a
    stuck holder (a network home) must not freeze it. OSError when it cannot."""
    for _ in range(LOCK_TRIES):
        try:
            _try_lock(fd)
            return
        except OSError:
            time.sleep(LOCK_PAUSE)
    raise OSError("the history file is locked by another console")


try:
    import fcntl

    def _try_lock(fd: int) -> None:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)

    def _unlock(fd: int) -> None:
        fcntl.flock(fd, fcntl.LOCK_UN)

except ImportError:  # Windows
    import msvcrt

    def _try_lock(fd: int) -> None:
        os.lseek(fd, 0, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)  # type: ignore[attr-defined]

    def _unlock(fd: int) -> None:
        os.lseek(fd, 0, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)  # type: ignore[attr-defined]
