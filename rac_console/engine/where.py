"""Where a command can run: the console, the REPL, a script, the command line.

Apart from the registry, which loads the command language, so that an engine can be
made (the console makes one before its first paint) without loading any command.
"""

from __future__ import annotations

from enum import Enum


class Where(Enum):
    """Where a command can run."""

    CONSOLE = "console"
    REPL = "REPL"
    RUN = "run"  # a line of rac-console run FILE
    COMMAND_LINE = "command line"  # rac-console get, put, send, latency


AT_A_TERMINAL = frozenset({Where.CONSOLE, Where.REPL})
EVERYWHERE = frozenset(Where)
