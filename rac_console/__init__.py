"""rac-console: a terminal console for DENSO RC8 controllers speaking RAC, and a library
for Python scripts::

    import rac_console as rac

    with rac.connect("sim") as rc:
        rc.put("I", 10, 5)
        print(rc.get("I", 10))

Each name loads with its module when first used (:mod:`rac_console.lazy`): the command
line (``python -m rac_console``) loads none of the library.
"""

from typing import TYPE_CHECKING, Any

from .lazy import exports

if TYPE_CHECKING:
    from . import aio
    from .library.cell import Cell, cell
    from .library.connection import Connection, connect
    from .library.errors import (
        ConnectionFailed,
        ControllerError,
        OutcomeUnknown,
        RacError,
        ReadBackMismatch,
        Refused,
        Timeout,
        UnknownTarget,
        UnreadableReply,
    )
    from .library.results import Reading, Sent, Value, Written

from .release import __version__ as __version__

_names = exports(
    __name__,
    {
        **dict.fromkeys(("Cell", "cell"), ".library.cell"),
        **dict.fromkeys(("Connection", "connect"), ".library.connection"),
        **dict.fromkeys(
            (
                "ConnectionFailed",
                "ControllerError",
                "OutcomeUnknown",
                "RacError",
                "ReadBackMismatch",
                "Refused",
                "Timeout",
                "UnknownTarget",
                "UnreadableReply",
            ),
            ".library.errors",
        ),
        **dict.fromkeys(("Reading", "Sent", "Value", "Written"), ".library.results"),
    },
)


def __getattr__(name: str) -> Any:
    """A public name, from its module when first used; ``aio`` is a module itself."""
    if name == "aio":
        from importlib import import_module

        return import_module(".aio", __name__)
    return _names(name)


__all__ = [
    "Cell",
    "Connection",
    "ConnectionFailed",
    "ControllerError",
    "OutcomeUnknown",
    "RacError",
    "ReadBackMismatch",
    "Reading",
    "Refused",
    "Sent",
    "Timeout",
    "UnknownTarget",
    "UnreadableReply",
    "Value",
    "Written",
    "aio",
    "cell",
    "connect",
]
