"""The session: the only client code that touches sockets.

``machine`` holds the protocol rules without I/O; ``blocking`` drives them over one
blocking socket, owned by one thread.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from .blocking import Session
    from .types import (
        DEFAULT_PORT,
        DEFAULT_TIMEOUT,
        BadReply,
        ConnectFailed,
        Disconnected,
        Frame,
        NotSent,
        Reply,
        RequestTimeout,
        State,
        TransportError,
    )

#: Each name from its module when first used (:mod:`rac_console.lazy`): a frame or an
#: error type does not load the socket code.
__getattr__ = exports(
    __name__,
    {
        "Session": ".blocking",
        **dict.fromkeys(
            (
                "DEFAULT_PORT",
                "DEFAULT_TIMEOUT",
                "BadReply",
                "ConnectFailed",
                "Disconnected",
                "Frame",
                "NotSent",
                "Reply",
                "RequestTimeout",
                "State",
                "TransportError",
            ),
            ".types",
        ),
    },
)

__all__ = [
    "DEFAULT_PORT",
    "DEFAULT_TIMEOUT",
    "BadReply",
    "ConnectFailed",
    "Disconnected",
    "Frame",
    "NotSent",
    "Reply",
    "RequestTimeout",
    "Session",
    "State",
    "TransportError",
]
