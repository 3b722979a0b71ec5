"""The session: the only client code that touches sockets.

``machine`` holds the protocol rules without I/O; ``blocking`` drives them over one
blocking socket, owned by one thread.
"""

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
