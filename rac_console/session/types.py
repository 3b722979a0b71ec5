"""What a session hands out: frames, replies, states and the ways an exchange fails."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, NamedTuple

from ..protocol.errors import RacError

if TYPE_CHECKING:
    from ..protocol import RequestLine, Response

DEFAULT_PORT = 5006
DEFAULT_TIMEOUT = 2.0
MAX_REPLY_LINE = 64 * 1024

Direction = Literal["tx", "rx"]
State = Literal["closed", "connecting", "connected"]


class TransportError(RacError):
    """The exchange failed on the way: no trustworthy reply came."""

    def __init__(self, message: str, raw: bytes | None = None) -> None:
        super().__init__(message)
        self.raw = raw


#: Why a connection could not be opened, as the status line says it.
ConnectProblem = Literal["refused", "unreachable", "timed out", "unknown host", "failed"]


class ConnectFailed(TransportError):
    """No connection could be opened: nothing was sent. ``problem`` says why in a word."""

    def __init__(
        self, message: str, raw: bytes | None = None, *, problem: ConnectProblem = "failed"
    ) -> None:
        super().__init__(message, raw)
        self.problem: ConnectProblem = problem


class RequestTimeout(TransportError):
    pass


class Disconnected(TransportError):
    """The connection ended. ``before_reply``: no byte of the reply had come."""

    def __init__(
        self, message: str, raw: bytes | None = None, *, before_reply: bool = False
    ) -> None:
        super().__init__(message, raw)
        self.before_reply = before_reply


class NotSent(TransportError):
    """The job was cancelled before its request went out: nothing was sent."""


class BadReply(TransportError):
    """A reply came but cannot be parsed or cannot belong to the request."""


@dataclass(frozen=True, slots=True)
class Frame:
    """One frame that crossed the wire, for logs and recorders.

    ``data`` holds the bytes as they crossed, CR included; a fragment cut off by a
    closed connection has no CR. A reply to a request carries its ``rtt`` and what
    the session made of it: the parsed ``response``, or the ``problem`` that made it
    refuse the reply. Nobody parses a reply again.

    ``request`` is what the request line says (read once, when the request was made
    from the bytes sent): a sent frame's own, a reply's (or a reply cut short's) the one
    it answered, as the session knows it; None for a line nobody asked for.
    """

    time: float
    direction: Direction
    data: bytes
    rtt: float | None = None
    unsolicited: bool = False
    poll: bool = False
    response: Response | None = None
    problem: str | None = None
    request: RequestLine | None = None
    #: Who asked, when the connection is an agent's, shared by its clients: the client
    #: named (``console 2``), for the frames of another client's request.
    source: str | None = None


class Reply(NamedTuple):
    """The reply that answered a request, parsed and checked. A named tuple: built on
    every exchange, it costs a third of a frozen dataclass."""

    raw: bytes
    response: Response
    rtt: float

    @property
    def text(self) -> str:
        return self.raw.decode("ascii")


FrameObserver = Callable[[Frame], None]
StateObserver = Callable[[State], None]
