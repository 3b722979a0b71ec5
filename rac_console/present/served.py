"""Whether this console is served to a browser by ``rac-console serve``: its status line
says so, and it starts though its standard streams are pipes, not a terminal."""

from __future__ import annotations

from rich.text import Text

# Whether this process is a served console: decided where the place is (the engine's).
from ..engine.setup.where import SERVED_ENV as SERVED_ENV
from ..engine.setup.where import WEB_DRIVER as WEB_DRIVER
from ..engine.setup.where import served as served

#: The sizes a served screen may have, in cells each way: what a browser asks for, by
#: message or typed in as keys, is brought within them (serve's parts, the console's
#: driver).
SMALLEST_SCREEN, LARGEST_SCREEN = 10, 1000


def within_screen(cells: int) -> int:
    return max(SMALLEST_SCREEN, min(cells, LARGEST_SCREEN))


#: What leads a served console's status line.
SERVED_BADGE = Text.assemble(("SERVED", "bold black on cyan"), " ")
