"""The outbox keeps a reader that stops draining from growing without bound."""

from __future__ import annotations

import pytest

from rac_console.engine import Cycle, Note, Outbox
from rac_console.engine.published import outbox as outbox_module


def test_cycles_are_shed_oldest_first_and_counted_like_frames(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(outbox_module, "MAX_EVENTS", 100)
    outbox = Outbox()
    outbox.put(Note("kept", 0.0))
    for n in range(1000):  # a console at interval 0 whose screen stopped draining
        outbox.put(Cycle(float(n), float(n), ()))
    outbox.put_many([Cycle(float(n), float(n), ()) for n in range(1000, 1040)])
    for n in range(1040, 1500):
        outbox.put(Cycle(float(n), float(n), ()))
    batch = outbox.drain()
    assert len(batch.events) <= 101
    assert batch.events[0] == Note("kept", 0.0)  # never a note
    times = [event.time for event in batch.events if isinstance(event, Cycle)]
    assert times == sorted(times) and times[-1] == 1499.0  # the newest are kept
    assert batch.cycles_dropped == 1500 - len(times)
    assert batch.frames_dropped == 0
