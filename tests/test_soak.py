"""Soak: 100 variables polled through the console engine against a misbehaving simulator.

Runs for RAC_SOAK_SECONDS (default 15 in CI; set it to 600 or more by hand for a long
run). Checks that no exception escapes, memory stays flat with the log bounded, every
frame that crossed the wire is in the --record file once and in order, and each value
shown is the one the simulator sent in reply to that variable's request.
"""

from __future__ import annotations

import asyncio
import collections
import json
import os
import time
import tracemalloc
from pathlib import Path
from typing import cast

import pytest

from rac_console.engine import Alert, Engine, Note, Result, RowView
from rac_console.engine.polling.backoff import MAX_DELAY
from rac_console.protocol import RacError, Response, Variant, escape_bytes, parse_response
from rac_console.session import Frame
from rac_console.sim.controller import SimulatedController
from rac_console.sim.faults import FaultSettings
from rac_console.sim.server import SimulatorServer

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

SECONDS = float(os.environ.get("RAC_SOAK_SECONDS", "15"))
VARIABLES = 100
#: At least this many polls make a soak: it runs SECONDS, and on past them (up to
#: DEADLINE more) until it has them, so a busy machine makes it longer, not a failure.
ENOUGH_POLLS = 4 * VARIABLES + 1
#: With no poll for this long polling has stopped (the backoff between tries is at most
#: MAX_DELAY, its bound checked in test_reconnect_backoff; the rest is a busy machine).
STOPPED = MAX_DELAY + 15
DEADLINE = 120.0
FAULTS = FaultSettings(
    jitter_ms=1,
    drop_every=97,
    stall_every=89,
    garble_every=83,
    extra_every=71,
    error_rate=0.01,
    seed=11,
)


def own_memory(snapshot: tracemalloc.Snapshot) -> int:
    """Bytes held by the client side: everything but the test's transcript of the server."""
    filtered = snapshot.filter_traces(
        [
            tracemalloc.Filter(False, "*/sim/server.py"),
            tracemalloc.Filter(False, "*/tests/*"),
            tracemalloc.Filter(False, tracemalloc.__file__),
        ]
    )
    return sum(stat.size for stat in filtered.statistics("filename"))


async def soak(record: Path) -> dict:
    simulator = SimulatorServer(faults=FAULTS, transcript=True)
    controller = cast(SimulatedController, simulator.controller)  # not a replay
    # Every reply is unique: the variable's index and the request count at that moment.
    controller.value = lambda kind, index: index * 100_000 + controller.requests  # type: ignore[method-assign]
    await simulator.start()
    log: collections.deque = collections.deque(maxlen=5000)  # bounded, like the frame log
    rows: dict = {}
    answered: set[str] = set()
    alerts: list[str] = []
    polls = 0

    def drain() -> int:
        """Take what the engine published, as the console does on its tick; polls sent."""
        batch = engine.outbox.drain()
        rows.update(batch.rows)
        log.extend(batch.events)
        answered.update(e.line or "" for e in batch.events if isinstance(e, Result))
        alerts.extend(e.text for e in batch.events if isinstance(e, Alert))
        return sum(
            1 for e in batch.events if isinstance(e, Frame) and e.poll and e.direction == "tx"
        )

    engine = Engine(simulator.host, simulator.port, timeout=0.3, interval=0, record=str(record))
    tracemalloc.start()
    await asyncio.to_thread(engine.start)
    try:
        engine.submit(f"watch I 0-{VARIABLES - 1}")
        started = time.monotonic()
        while time.monotonic() - started < SECONDS / 3:
            await asyncio.sleep(0.1)
            polls += drain()
        early = own_memory(tracemalloc.take_snapshot())
        last_poll = time.monotonic()
        while time.monotonic() - started < SECONDS or polls < ENOUGH_POLLS:
            assert time.monotonic() - started < SECONDS + DEADLINE, f"only {polls} polls"
            await asyncio.sleep(0.25)
            new_polls = drain()
            if new_polls:
                last_poll = time.monotonic()
            assert time.monotonic() - last_poll < STOPPED, "polling stopped"
            polls += new_polls
        late = own_memory(tracemalloc.take_snapshot())
        engine.submit("pause")
        deadline = time.monotonic() + 20
        while "pause" not in answered:
            assert time.monotonic() < deadline, "the pause was not answered"
            await asyncio.sleep(0.05)
            polls += drain()
        notes = [event.text for event in log if isinstance(event, Note)]
    finally:
        tracemalloc.stop()
        await asyncio.to_thread(engine.stop)
        await simulator.stop()
    views: dict[int, RowView] = {var.index: view for var, view in rows.items()}
    return {
        "early": early,
        "late": late,
        "rows": {index: view.variant for index, view in views.items()},
        "notes": notes,
        "alerts": alerts,
        "polls": polls,
        "transcript": simulator.transcript,
    }


#: It runs SECONDS, up to DEADLINE more, then up to 20 s for the pause and the checks
#: over the record: beyond the suite's per-test timeout (pyproject.toml) when CI gives it
#: two minutes.
@pytest.mark.timeout(SECONDS + DEADLINE + 120)
def test_soak(tmp_path: Path) -> None:
    record = tmp_path / "frames.jsonl"
    result = asyncio.run(soak(record))
    frames = [json.loads(line) for line in record.read_text().splitlines()]
    transcript = [entry for entry in result["transcript"] if not entry[1].startswith(b"SIM:")]

    assert result["alerts"] == []  # the engine never stopped on an internal error
    growth = result["late"] - result["early"]
    assert growth < max(2_000_000, 0.2 * result["early"]), f"memory grew by {growth} bytes"

    # Every request that crossed the wire is in the record once, in order.
    sent = [f["text"] for f in frames if f["dir"] == "tx"]
    received_by_server = [escape_bytes(line) for _, line, _ in transcript]
    assert sent[: len(received_by_server)] == received_by_server
    assert len(sent) - len(received_by_server) <= 1

    # The reply taken for each request is the one the simulator sent for it.
    replies = {n: reply for n, (_, _, reply) in enumerate(transcript)}
    accepted: dict[int, Variant] = {}
    request = -1
    for frame in frames:
        if frame["dir"] == "tx":
            request += 1
            continue
        if "rtt_ms" not in frame or "refused" in frame:
            continue  # unsolicited, cut off or refused: never taken as an answer
        sent_reply = replies.get(request)
        assert sent_reply is not None, f"request {request} got an answer the server never sent"
        assert frame["text"] == escape_bytes(sent_reply[:-1])
        response = _parsed(frame["text"])
        if response is not None and response.ok and response.variant is not None:
            index = int(sent[request].split(":")[2])
            accepted[index] = response.variant
    assert len(accepted) == VARIABLES
    for index, variant in result["rows"].items():
        assert variant == accepted[index], f"I{index} shows {variant}, last reply {accepted[index]}"


def _parsed(text: str) -> Response | None:
    try:
        return parse_response(text)
    except RacError:
        return None  # a garbled reply: recorded, never a value
