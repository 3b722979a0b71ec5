"""What a command says besides an exchange's outcome: a message, or a step only a
front end can take.

Apart from the other events (:mod:`.events`): every pane of the console says things,
and the console's panes load before its first paint, the command language after it.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum


@dataclass(frozen=True, slots=True)
class Message:
    """Feedback that is not an exchange: help text, a confirmation, an error."""

    text: str
    level: str = "info"  # info, error


class UiStep(Enum):
    """What only a front end can do."""

    CLEAR = "clear"  # its log or screen
    QUIT = "quit"
    FRAMES_ON = "frames on"  # echo frames (REPL) / show poll frames (console)
    FRAMES_OFF = "frames off"
