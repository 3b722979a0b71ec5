"""Error types of the pure protocol layer.

Every failure the protocol code can detect is one of these, so a front end can
catch ``RacError`` and show its message, never a traceback.
"""

from __future__ import annotations


class RacError(Exception):
    """Base of every error raised by rac_console's own code."""


class ProtocolError(RacError):
    """Text received from a peer does not follow the RAC grammar."""


class InputError(RacError):
    """What a user typed cannot become a request; the message says how to fix it.

    Always raised before anything is sent.
    """


class EncodeError(InputError):
    """A value cannot be written as RAC text (refused before sending)."""


class FrameTooLong(ProtocolError):
    """A line grew past the decoder's bound without a CR.

    ``lines`` holds the complete lines that came before it in the same chunk.
    """

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.lines: list[bytes] = []
