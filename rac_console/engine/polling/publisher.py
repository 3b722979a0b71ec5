"""The engine's side of the outbox: events batched, notes and alerts, row views.

Frames and notes are handed over in batches (one lock per batch, not per frame);
results, alerts and the questions a front end must answer go at once.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

from ...commands.language import VarRef
from ...session import Frame
from ..files.frame_files import FrameFiles
from ..published.events import Alert, Event, Note, RowView
from ..published.outbox import Outbox
from ..watch.rows import WatchRow

if TYPE_CHECKING:
    from .plant_tap import PlantTap

#: Events are handed to the outbox in batches at least this often while polling (and at
#: once when the engine goes idle or answers a line).
EVENTS_EVERY = 0.01


class Publisher:
    """Owned by the engine's thread; :attr:`outbox` is the only thing another reads."""

    def __init__(self, outbox: Outbox, files: FrameFiles, frames: bool = True) -> None:
        """``frames``: publish every frame (a front end that shows none saves the work)."""
        self.outbox = outbox
        self.files = files
        self._frames = frames
        #: A front end shows poll frames (the console's log does; the REPL never does).
        self.poll_frames = frames
        self.observers: list[Callable[[Frame], None]] = []  # Engine.add_frame_observer
        #: Who asked for the job running now, when not a typed line (``OPC UA``).
        self.source: str | None = None
        self._events: list[Event] = []
        #: Row views since the last flush, handed over with the events: a front end
        #: never sees a row change before the frames and notes that came before it.
        self._rows: dict[VarRef, RowView] = {}
        self._events_at = 0.0  # perf_counter() of the last flush
        #: Something the status line shows changed: published when the loop next idles.
        self.status_dirty = True
        #: The plant's feed (MQTT, /metrics): handed the rows that changed at each flush.
        self.tap: PlantTap | None = None

    def emit(self, event: Event) -> None:
        """Queue an event for the outbox (handed over by :meth:`flush`)."""
        self._events.append(event)

    def flush(self) -> None:
        if self._rows and self.tap is not None:
            self.tap.rows(self._rows.values())
        if self._events or self._rows:
            self.outbox.put_many(self._events, self._rows)
            self._events, self._rows = [], {}
        self._events_at = time.perf_counter()

    def flush_due(self) -> None:
        """Flush when the last flush is EVENTS_EVERY old (polling flat out, with no
        frame to carry the events out)."""
        if time.perf_counter() - self._events_at > EVENTS_EVERY:
            self.flush()

    def frame(self, frame: Frame) -> None:
        """A frame crossed the wire: to the files, and to the front ends in a batch."""
        if self.source is not None and frame.source is None and not frame.poll:
            frame = replace(frame, source=self.source)
        self.files.frame(frame)
        for observer in self.observers:
            observer(frame)
        if self._frames:
            self._events.append(frame)
            # The request in flight, for the status line's "waiting for a reply": set as
            # a request leaves, cleared by its reply or by the connection's end.
            self.outbox.waiting_since = time.perf_counter() if frame.direction == "tx" else None
        if time.perf_counter() - self._events_at > EVENTS_EVERY:
            self.flush()  # during a long command (latency)

    def polls_observed(self) -> bool:
        """Whether a poll's frames go anywhere: shown, recorded, transcribed or observed.
        When not, the session builds none (two objects a poll that nobody reads)."""
        files = self.files
        return bool(self.poll_frames or files.recorder or files.transcript or self.observers)

    def note(self, text: str) -> None:
        """A mark in the frame log (and the transcript)."""
        now = time.time()
        self.files.note(text, now)
        self.emit(Note(text, now))

    def alert(self, text: str) -> None:
        """Said at once, whatever the user is doing."""
        self.files.note(text, time.time())
        self.emit(Alert(text))
        self.flush()

    def show_row(self, row: WatchRow) -> None:
        """The row as it stands now, handed over at the next flush (the last view wins)."""
        self._rows[row.var] = row.view()

    def remove_rows(self, variables: list[VarRef]) -> None:
        """Rows unwatched: none of their views still to go out may bring them back."""
        for var in variables:
            self._rows.pop(var, None)
        if self.tap is not None:
            self.tap.removed(variables)
        self.flush()
        self.outbox.put_removed(variables)
