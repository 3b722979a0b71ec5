"""From an engine's batch to what a front end does with it: the one switch over events.

The console, the REPL, the CLI's live runs and the tests' fronts all read batches the
same way: the status first, then the rows, then the events in the order published, then
what was shed. A front end subclasses :class:`BatchReader` and overrides the methods
for what it shows; the rest do nothing. No front end checks an event's type itself.

The events' module loads when the first event arrives: the console's first paint reads
batches that hold only a status.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..commands.language import VarRef
    from ..engine.published.events import Alert, ConfirmWrite, Cycle, Note, Result
    from ..engine.published.outbox import Batch
    from ..engine.published.status import Status
    from ..session import Frame


class BatchReader:
    """What a front end does with each kind of thing an engine publishes, by target
    (``target`` None: the cell's own batch, which holds results and alerts only)."""

    def read(self, target: str | None, batch: Batch) -> None:
        """One batch, in the order every front end takes it."""
        if target is not None:
            if batch.status is not None:
                self.take_status(target, batch.status)
            self.take_rows(target, batch)
        if batch.events:
            self._read_events(target, batch)
        if batch.frames_dropped or batch.cycles_dropped:
            self.take_shed(target, batch.frames_dropped, batch.cycles_dropped)

    def _read_events(self, target: str | None, batch: Batch) -> None:
        from ..engine.published.events import Alert, ConfirmWrite, Cycle, Note, Result

        for event in batch.events:
            if isinstance(event, Result):
                self.take_result(target, event)
            elif isinstance(event, Cycle):
                self.take_cycle(target, event)
            elif isinstance(event, ConfirmWrite):
                self.take_confirm(target, event)
            elif isinstance(event, Alert):
                self.take_alert(target, event)
            elif isinstance(event, Note):
                self.take_note(target, event)
            else:
                self.take_frame(target, event)

    # What a front end may take; each does nothing unless overridden.

    def take_status(self, target: str, status: Status) -> None:
        """The target's latest status (only the newest since the last drain)."""

    def take_rows(self, target: str, batch: Batch) -> None:
        """The target's rows changed (``batch.rows``) or went (``batch.removed``)."""

    def take_result(self, target: str | None, result: Result) -> None:
        """What came of a submitted line."""

    def take_cycle(self, target: str | None, cycle: Cycle) -> None:
        """A poll cycle's readings (the trends', the CLI's live lines)."""

    def take_confirm(self, target: str | None, question: ConfirmWrite) -> None:
        """A write waits for a yes."""

    def take_alert(self, target: str | None, alert: Alert) -> None:
        """Something to tell at once (a file failed, the plant's news)."""

    def take_note(self, target: str | None, note: Note) -> None:
        """A mark in the frame log (a gap, a request with no trustworthy reply)."""

    def take_frame(self, target: str | None, frame: Frame) -> None:
        """A frame crossed the wire."""

    def take_shed(self, target: str | None, frames: int, cycles: int) -> None:
        """Frames or poll cycles shed because the reader fell behind."""


def removed_rows(batch: Batch) -> set[VarRef]:
    """The rows a batch removed and did not add back."""
    return batch.removed - batch.rows.keys()
