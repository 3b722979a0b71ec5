"""The built-in commands, each declared once with its handler (see :mod:`..registry`).

A module groups the commands that share their parts; adding a command is one entry in
one of them (or :meth:`~..registry.Registry.register` at run time).
"""

from __future__ import annotations

from ..registry import Registry
from . import connection, exchanges, frames, publishing, watching

#: In the order ``help`` lists them.
BUILTIN = Registry(
    [
        *exchanges.SPECS[:3],  # get, put, send
        *watching.SPECS,  # watch, unwatch, interval, pause, resume
        *connection.SPECS,  # connect, disconnect
        *watching.FILE_SPECS,  # save, load
        frames.FRAMES_SPEC,
        *exchanges.SPECS[3:],  # latency, wait
        watching.LOG_SPEC,
        publishing.PUBLISH_SPEC,
        *frames.FILE_SPECS,  # record, transcript
        *frames.CONSOLE_SPECS,  # clear, help, quit
    ]
)

__all__ = ["BUILTIN"]

#: One line of the command language (None for a blank line or a comment).
parse_command = BUILTIN.parse
#: The text of ``help`` or ``help COMMAND``.
help_lines = BUILTIN.help_lines

__all__ += ["help_lines", "parse_command"]
