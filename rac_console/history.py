"""Command history shared by the console and the REPL: one file, bounded, owner-only.

The file holds one command per line (commands never contain a newline), oldest
first. Consecutive duplicates are not stored; the file is trimmed to the newest
``limit`` entries when it grows past twice that.
"""

from __future__ import annotations

import os
from pathlib import Path

from .recorder import open_private

DEFAULT_LIMIT = 1000


def default_history_path() -> Path:
    from platformdirs import user_state_path

    return user_state_path("rac-console") / "history"


class History:
    def __init__(self, path: Path | str, limit: int = DEFAULT_LIMIT) -> None:
        self.path = Path(path)
        self.limit = limit
        self.entries: list[str] = self._read()[-limit:]
        self._lines_in_file = len(self.entries)

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
            if self._lines_in_file >= 2 * self.limit:
                self._rewrite()
            else:
                with open_private(str(self.path)) as handle:
                    handle.write(line + "\n")
                self._lines_in_file += 1
        except OSError:
            pass  # history is a convenience: a read-only home must not stop the console

    def _rewrite(self) -> None:
        temporary = self.path.with_suffix(".tmp")
        with open_private(str(temporary), "w") as handle:
            handle.write("".join(entry + "\n" for entry in self.entries))
        os.replace(temporary, self.path)
        self._lines_in_file = len(self.entries)
