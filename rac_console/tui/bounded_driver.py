"""A served console's screen stays within a size a screen can have.

The browser's resize messages are clamped by ``rac-console serve``, but Textual's input
parser also takes a resize typed in as an escape sequence (``ESC [ 48 ; ROWS ; COLS ;
... t``), which reaches the console as keys: one asking for 100,000 rows grew a console
by 40 MB a second. Every resize event is clamped here, on its way from the driver.
"""

from __future__ import annotations

from textual import events
from textual.driver import Driver
from textual.geometry import Size
from textual.message import Message

from ..present.served import within_screen


def bounded(size: Size) -> Size:
    return Size(within_screen(size.width), within_screen(size.height))


def bounded_driver(base: type[Driver]) -> type[Driver]:
    """``base`` (the web driver a served console runs on) with every resize clamped."""

    class BoundedDriver(base):  # type: ignore[valid-type, misc]
        def process_message(self, message: Message) -> None:
            if isinstance(message, events.Resize):
                message = events.Resize(bounded(message.size), bounded(message.virtual_size))
            super().process_message(message)

    return BoundedDriver
