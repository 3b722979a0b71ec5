"""Where a command can run: the console, the REPL, a script, the command line, the
console served to a browser; and what each place may reach besides its targets.

Apart from the registry, which loads the command language, so that an engine can be
made (the console makes one before its first paint) without loading any command.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from enum import Enum

from ...commands.reach import Reach


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
#: Where the built-in simulator (no -H) listens on no port: the console reaches it over a
#: socket pair of its own process, so no other process or user of the machine serving
#: it can read or write it, whatever the session may write. Elsewhere it listens on
#: 127.0.0.1, where the user's other tools can reach it (the command line says where).
UNLISTED_SIMULATOR = frozenset({Where.SERVED})


def reaches(where: Where, reach: Reach) -> bool:
    """Whether a command, or a setting of the config file, that reaches ``reach`` is
    for ``where``: a console served to a browser reaches its targets and nothing else
    of the machine serving it (no file, no other host). The one rule: the registry asks
    it of each command's spec, the config file's reader of each key."""
    return reach is Reach.TARGET or where is not Where.SERVED


#: Set in a served session's environment: the console runs under textual-serve's web
#: driver, its standard streams are pipes to the server, not a terminal.
SERVED_ENV = "RAC_CONSOLE_SERVED"

#: What textual-serve sets ``TEXTUAL_DRIVER`` to in the processes it starts.
WEB_DRIVER = "textual.drivers.web_driver:WebDriver"


def served(environ: Mapping[str, str] | None = None) -> bool:
    """True in a console started by ``rac-console serve``: the web driver is set and the
    served marker too (either alone is someone's environment, not a served session)."""
    env = os.environ if environ is None else environ
    return env.get("TEXTUAL_DRIVER") == WEB_DRIVER and env.get(SERVED_ENV) == "1"


def this_process() -> Where:
    """The place this process's settings are read for: a served console, or (anywhere
    else, where every setting is read) the console."""
    return Where.SERVED if served() else Where.CONSOLE
