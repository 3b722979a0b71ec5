"""Command history shared by the console and the REPL: one file, bounded, owner-only.

The file holds one command per line (commands never contain a newline), oldest
first. Consecutive duplicates are not stored; the file is trimmed to the newest
``limit`` entries when it grows past twice that.

Several consoles may share the file: each appends, and a trim keeps the newest
lines *of the file* (not of one console's memory), under a lock that appends take
too, so no console's entries are lost and none is written to a file being replaced.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Iterator
from pathlib import Path

from ..engine.recorder import open_private

DEFAULT_LIMIT = 1000


def default_history_path() -> Path:
    from platformdirs import user_state_path

    return user_state_path("rac-console") / "history"


class History:
    def __init__(self, path: Path | str, limit: int = DEFAULT_LIMIT) -> None:
        self.path = Path(path)
        self.limit = limit
        lines = self._read()
        self.entries: list[str] = lines[-limit:]
        # A file left long by an earlier run is trimmed at this run's first append.
        self._appends = limit if len(lines) >= 2 * limit else 0
        with contextlib.suppress(OSError):  # an older file may be readable by others
            if self.path.exists():
                self.path.chmod(0o600)

    def _read(self) -> list[str]:
        try:
            text = self.path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            return []
        return [line for line in text.split("\n") if line.strip()]

    def append(self, line: str) -> None:
        """Remember a command; blank lines and repeats of the last one are skipped."""
        line = line.replace("\r", " ").replace("\n", " ")
        if not line.strip() or (self.entries and self.entries[-1] == line):
            return
        self.entries.append(line)
        del self.entries[: -self.limit]
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
        lines = self._read()
        if len(lines) < 2 * self.limit:
            return
        temporary = self.path.with_name(self.path.name + ".tmp")
        with open_private(str(temporary), "w") as handle:
            handle.write("".join(entry + "\n" for entry in lines[-self.limit :]))
        os.replace(temporary, self.path)


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
