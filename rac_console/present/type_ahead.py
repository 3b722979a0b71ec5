"""Which typed lines may stop to ask before they write, on a ``confirm`` target.

The console holds the keys typed right after such a line (see
:class:`~rac_console.tui.command_line.CommandLine`): typed ahead of a question, a ``y``
and an Enter must neither answer it nor run as a command once it is answered. Pure: the
line is read with the command language, as the engine will read it.
"""

from __future__ import annotations

from ..commands.language import Put, Raw
from ..engine.commands import BUILTIN
from ..protocol.errors import InputError


def may_ask(line: str) -> bool:
    """True for a ``put`` and any raw line but a well-formed GET: the lines a confirm
    target's rules apply to (the engine may refuse them without asking; never the
    other way round). A line that does not parse is refused before anything is asked."""
    try:
        command = BUILTIN.parse(line)
    except InputError:
        return False
    return isinstance(command, Put) or (
        isinstance(command, Raw) and not command.request.read_only_safe
    )
