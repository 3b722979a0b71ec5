"""A served console's driver: what reaches the console from the browser, bounded.

- **Resizes.** The browser's resize messages are clamped by ``rac-console serve``, but
  Textual's input parser also takes a resize typed in as an escape sequence (``ESC [ 48 ;
  ROWS ; COLS ; ... t``), which reaches the console as keys: one asking for 100,000 rows
  grew a console by 40 MB a second. Every resize event is clamped here, on its way from
  the driver.
- **Keys.** Each key is an event the console handles on its own; a page (or anything
  that holds its socket) can send thousands in one message. Keys past a budget
  (:data:`~..present.served_bounds.KEYS_AT_ONCE`, then
  :data:`~..present.served_bounds.KEYS_PER_SECOND`) are dropped here, before they are
  queued, and the console says how many (:class:`InputDropped`). A paste is one event
  and goes whole; input serve dropped (a message too big or too fast) is said the same
  way, serve telling the driver with a meta message. The mouse's moves and wheel steps
  have a budget of the same size, and past it are dropped unsaid.
- **Deliveries.** A screenshot is delivered to the browser through the driver, which
  keeps the file until the browser has downloaded it: one the browser never asks for
  stayed for good (3 to 13 MB each). At most :data:`DELIVERIES_KEPT` wait; a newer one
  drops the oldest that no download has started.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO, Literal, TextIO

from textual import events
from textual.driver import Driver
from textual.geometry import Size
from textual.message import Message

from ..present.served import within_screen
from ..present.served_bounds import DROPPED_META, KEYS_AT_ONCE, KEYS_PER_SECOND, Budget

#: Deliveries (screenshots) kept for a browser that has not downloaded them.
DELIVERIES_KEPT = 3
#: How long after input was first dropped the console says so (with all dropped since).
SAY_AFTER = 0.5


#: The mouse's events bounded as keys are (each one a hover or a scroll to work out): its
#: moves and its wheel, not its buttons (a press kept and its release dropped would leave
#: a button held).
MOVES = (
    events.MouseMove,
    events.MouseScrollDown,
    events.MouseScrollUp,
    events.MouseScrollLeft,
    events.MouseScrollRight,
)


def bounded(size: Size) -> Size:
    return Size(within_screen(size.width), within_screen(size.height))


class Dropped:
    """What was dropped since the console last said so: keys (by the driver) and bytes
    (by serve). Counted on the driver's thread; ``say`` is called :data:`SAY_AFTER`
    seconds after the first of them, on a thread of its own, so that a flood is a line
    or two, not one per key; the app takes the counts on its own thread."""

    def __init__(self, say: Callable[[Dropped], object]) -> None:
        self._say = say
        self._lock = threading.Lock()
        self._counted = (0, 0)
        self._pending = False

    def add(self, keys: int = 0, size: int = 0) -> None:
        with self._lock:
            first = not self._pending
            self._pending = True
            self._counted = (self._counted[0] + keys, self._counted[1] + size)
        if first:
            timer = threading.Timer(SAY_AFTER, self._say, (self,))
            timer.daemon = True
            timer.start()

    def take(self) -> tuple[int, int]:
        """The keys and bytes dropped since the last time (counting starts again)."""
        with self._lock:
            taken, self._counted, self._pending = self._counted, (0, 0), False
            return taken


class InputDropped(Message):
    """Input from the browser was dropped: the console says what ``dropped`` counted
    (taken when it is handled, so a burst of drops is one line)."""

    def __init__(self, dropped: Dropped) -> None:
        super().__init__()
        self.dropped = dropped


def bounded_driver(base: type[Driver]) -> type[Driver]:
    """``base`` (the web driver a served console runs on) within the bounds above."""

    class BoundedDriver(base):  # type: ignore[valid-type, misc]
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            self._keys = Budget(KEYS_AT_ONCE, KEYS_PER_SECOND, time.monotonic())
            self._moves = Budget(KEYS_AT_ONCE, KEYS_PER_SECOND, time.monotonic())
            self._dropped = Dropped(lambda dropped: self._app.post_message(InputDropped(dropped)))
            self._started: set[str] = set()  # deliveries a download has asked for
            self._delivering = threading.Lock()

        def process_message(self, message: Message) -> None:
            if isinstance(message, events.Resize):
                message = events.Resize(bounded(message.size), bounded(message.virtual_size))
            elif isinstance(message, events.Key) and not self._keys.take(1, time.monotonic()):
                self._dropped.add(keys=1)
                return
            elif isinstance(message, MOVES) and not self._moves.take(1, time.monotonic()):
                return  # a move or a wheel's step: nothing a person misses, and unsaid
            super().process_message(message)

        def on_meta(self, packet_type: str, payload: dict[str, object]) -> None:
            if packet_type == DROPPED_META:
                size = payload.get("bytes")
                self._dropped.add(size=size if type(size) is int and size > 0 else 0)
            elif packet_type == "deliver_chunk_request":
                key = str(payload.get("key"))
                with self._delivering:
                    if key in self._deliveries:
                        self._started.add(key)
                        super().on_meta(packet_type, payload)
                    else:  # dropped: the download ends at once, empty
                        self.write_binary_encoded(("deliver_chunk", key, b""))
            else:
                super().on_meta(packet_type, payload)

        def deliver_binary(
            self,
            binary: BinaryIO | TextIO,
            *,
            delivery_key: str,
            save_path: Path,
            open_method: Literal["browser", "download"] = "download",
            encoding: str | None = None,
            mime_type: str | None = None,
            name: str | None = None,
        ) -> None:
            """The web driver's, keeping at most :data:`DELIVERIES_KEPT` files for
            downloads the browser has not started."""
            with self._delivering:
                waiting: dict[str, BinaryIO | TextIO] = self._deliveries
                never_asked = [key for key in waiting if key not in self._started]
                for key in never_asked[: max(0, len(never_asked) - DELIVERIES_KEPT + 1)]:
                    waiting.pop(key).close()
                self._started &= set(waiting)
            super().deliver_binary(
                binary,
                delivery_key=delivery_key,
                save_path=save_path,
                open_method=open_method,
                encoding=encoding,
                mime_type=mime_type,
                name=name,
            )

    return BoundedDriver
