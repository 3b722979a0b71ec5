"""Whether this console is served to a browser by ``rac-console serve``: its status line
says so, and it starts though its standard streams are pipes, not a terminal."""

from __future__ import annotations

import os
from collections.abc import Mapping

from rich.text import Text

#: Set in a served session's environment: the console runs under textual-serve's web
#: driver, its standard streams are pipes to the server, not a terminal.
SERVED_ENV = "RAC_CONSOLE_SERVED"

#: What textual-serve sets ``TEXTUAL_DRIVER`` to in the processes it starts.
WEB_DRIVER = "textual.drivers.web_driver:WebDriver"

#: The sizes a served screen may have, in cells each way: what a browser asks for, by
#: message or typed in as keys, is brought within them (serve's parts, the console's
#: driver).
SMALLEST_SCREEN, LARGEST_SCREEN = 10, 1000


def within_screen(cells: int) -> int:
    return max(SMALLEST_SCREEN, min(cells, LARGEST_SCREEN))


#: What leads a served console's status line.
SERVED_BADGE = Text.assemble(("SERVED", "bold black on cyan"), " ")


def served(environ: Mapping[str, str] | None = None) -> bool:
    """True in a console started by ``rac-console serve``: the web driver is set and the
    served marker too (either alone is someone's environment, not a served session)."""
    env = os.environ if environ is None else environ
    return env.get("TEXTUAL_DRIVER") == WEB_DRIVER and env.get(SERVED_ENV) == "1"
