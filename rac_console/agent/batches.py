"""What a client's engine publishes, sent to the client in batches.

One thread per client runs :func:`send`: a client that reads slowly holds only it, never
the polling. A batch goes at most every :data:`SEND_EVERY` seconds; rows and the status
in it replace the ones not yet sent, and poll frames are kept within a budget
(:class:`PollFrameBudget`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from ..commands.language import VarRef
from ..engine import Outbox, RowView, Status
from ..engine.published.events import Event
from ..session.shared import FrameBudget
from ..session.types import Frame
from .wire import Channel, ChannelClosed

#: The least time between two batches to one client (about a screen's refresh).
SEND_EVERY = 0.03
#: The most poll frames a second one client is sent (see :class:`PollFrameBudget`).
POLL_FRAMES_PER_SECOND = 2_000


def send_batches(
    outbox: Outbox,
    wake: threading.Event,
    channel: Channel,
    missed: Callable[[int], None],
    poll_frames_per_second: int = POLL_FRAMES_PER_SECOND,
    budget: FrameBudget | None = None,
) -> None:
    """Send the client what its engine publishes into ``outbox`` (``wake`` set when it
    does) until the channel closes; ``missed`` is told the frames the outbox shed.
    Rows and the status replace the ones not yet sent, so a batch carries the latest of
    each: a console polling 200 rows flat out gets about 30 batches a second to read,
    not one per poll, and its keys stay quick."""
    sent_rows: dict[VarRef, RowView] = {}  # as the client has them
    sent_status: Status | None = None
    polls = PollFrameBudget(poll_frames_per_second)
    while not channel.closed:
        wake.wait(0.5)
        wake.clear()
        batch = outbox.drain()
        events, left_out = polls.thin(batch.events)
        if budget is not None:  # the polls whose frames were never built for it
            left_out += budget.take_left_out()
        # A row or the status as the client already has it is not sent again.
        rows = {var: row for var, row in batch.rows.items() if sent_rows.get(var) != row}
        sent_rows.update(rows)
        for var in batch.removed:
            sent_rows.pop(var, None)
        status = batch.status if batch.status != sent_status else None
        sent_status = status or sent_status
        if not (events or rows or batch.removed or status or batch.frames_dropped or left_out):
            continue
        missed(batch.frames_dropped)
        try:
            channel.send(
                {
                    "op": "batch",
                    "events": events,
                    "polls_left_out": left_out,
                    "rows": rows,
                    "removed": batch.removed,
                    "status": status,
                    "frames_dropped": batch.frames_dropped,
                    "cycles_dropped": batch.cycles_dropped,
                }
            )
        except ChannelClosed:
            return
        time.sleep(SEND_EVERY)  # what comes meanwhile goes in the next batch


class PollFrameBudget:
    """At most :data:`POLL_FRAMES_PER_SECOND` poll frames a second to one client (a
    console showing its poll frames): the newest of each batch are sent, the older ones
    counted, and the client's log says how many were left out. A console polling 200
    rows flat out gets some 40,000 poll frames a second; decoding them all kept its keys
    waiting (p95 170 ms), and no one reads a log that scrolls that fast. Every other
    frame (a request, a write, a reply to one, a line nobody asked for) is always sent."""

    def __init__(self, per_second: int) -> None:
        self.rate = per_second
        self.allowance = float(self.rate)
        self.at = time.monotonic()

    def thin(self, events: list[Event]) -> tuple[list[Event], int]:
        """``events`` within the budget, and how many poll frames were left out."""
        now = time.monotonic()
        self.allowance = min(float(self.rate), self.allowance + (now - self.at) * self.rate)
        self.at = now
        polls = sum(1 for event in events if _is_poll_frame(event))
        keep = min(polls, int(self.allowance))
        self.allowance -= keep
        if keep == polls:
            return events, 0
        kept: list[Event] = []
        skip = polls - keep  # the oldest poll frames go
        for event in events:
            if skip and _is_poll_frame(event):
                skip -= 1
                continue
            kept.append(event)
        return kept, polls - keep


def _is_poll_frame(event: object) -> bool:
    return type(event) is Frame and event.poll and not event.unsolicited
