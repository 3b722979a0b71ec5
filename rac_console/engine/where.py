"""Where a command can run: the console, the REPL, a script, the command line, the
console served to a browser.

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
    SERVED = "served console"  # the console in a browser (rac-console serve)


#: A served console is a console too; what it refuses besides is the commands that
#: reach more of the machine serving it than its target (their spec's Traits.reaches).
AT_A_TERMINAL = frozenset({Where.CONSOLE, Where.REPL, Where.SERVED})
EVERYWHERE = frozenset(Where)
