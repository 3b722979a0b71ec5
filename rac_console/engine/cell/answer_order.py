"""A cell's drain in the order its lines answered, whichever targets answered them.

A cell's lines run one at a time, and the next starts as soon as the last one's
answer is out, on the thread of the target that ran it (no front end has to drain for
the queue to move). So one drain may hold several answers in the outboxes of several
targets: line 1's in robotB's batch, line 2's in robotA's, line 3's (``use``) in the
cell's own. The batches are taken at one instant (:meth:`Outbox.drain_together`), so
every answer before the last one in them is there too; read batch after batch, though,
robotA's line 2 would be read before robotB's line 1. Here each batch is cut after each
answer and the pieces merged by the answers' numbers (lines are numbered in the order
they were submitted), every target's own events kept in the order published.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..published.outbox import Batch

if TYPE_CHECKING:
    from ..published.events import Event

Drained = list[tuple[str | None, Batch]]


def in_answer_order(drained: Drained) -> Drained:
    """``drained`` (a batch for the cell, then one per target), cut and merged so that
    the answers come in the order of their numbers; as it is when at most one batch
    holds an answer (nothing to reorder: the usual case)."""
    from ..published.events import Result

    answering = [
        name for name, batch in drained if any(isinstance(e, Result) for e in batch.events)
    ]
    if len(answering) < 2:
        return drained
    queues = [_pieces(name, batch) for name, batch in drained]
    merged: Drained = []
    while any(queues):
        heads = [(queue[0][0], n) for n, queue in enumerate(queues) if queue]
        _, first = min(heads)  # the lowest number; on a tie, the first batch
        _, name, piece = queues[first].pop(0)
        merged.append((name, piece))
    return merged


def _pieces(name: str | None, batch: Batch) -> list[tuple[float, str | None, Batch]]:
    """``batch`` cut after each answer, each piece keyed by its answer's number (the
    piece after the last answer: after every answer). The first piece carries the
    batch's state (status, rows, what was shed), read before its events as ever."""
    from ..published.events import Result

    pieces: list[tuple[float, str | None, Batch]] = []
    events: list[Event] = []
    for event in batch.events:
        events.append(event)
        if isinstance(event, Result):
            pieces.append((event.seq, name, Batch(events)))
            events = []
    if events or not pieces:
        pieces.append((float("inf"), name, Batch(events)))
    head = pieces[0][2]
    head.rows, head.removed, head.status = batch.rows, batch.removed, batch.status
    head.frames_dropped, head.cycles_dropped = batch.frames_dropped, batch.cycles_dropped
    return pieces
