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

from rac_console.core import ConsoleCore
from rac_console.protocol import RacError, Response, Variant, escape_bytes, parse_response
from rac_console.sim.faults import FaultSettings
from rac_console.sim.server import SimulatorServer

SECONDS = float(os.environ.get("RAC_SOAK_SECONDS", "15"))
VARIABLES = 100
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
    controller = simulator.controller
    # Every reply is unique: the variable's index and the request count at that moment.
    controller.value = lambda kind, index: index * 100_000 + controller.requests  # type: ignore[method-assign]
    await simulator.start()
    log: collections.deque = collections.deque(maxlen=5000)  # bounded, like the frame log
    core = ConsoleCore(simulator.host, simulator.port, timeout=0.3, interval=0, record=str(record))
    core.add_log_listener(log.append)
    tracemalloc.start()
    await core.start()
    try:
        await core.handle_line(f"watch I 0-{VARIABLES - 1}")
        started = time.monotonic()
        while time.monotonic() - started < SECONDS / 3:
            await asyncio.sleep(0.1)
        early = own_memory(tracemalloc.take_snapshot())
        while time.monotonic() - started < SECONDS:
            await asyncio.sleep(0.1)
            assert core._poll_task is not None and not core._poll_task.done()
        late = own_memory(tracemalloc.take_snapshot())
        core.set_paused(True)
        await asyncio.sleep(0.5)  # let the cycle in flight end
        rows = {var.index: row.variant for var, row in core.watch.rows.items()}
        notes = [event for event in log if isinstance(event, str)]
    finally:
        tracemalloc.stop()
        await core.stop()
        await simulator.stop()
    return {
        "early": early,
        "late": late,
        "rows": rows,
        "notes": notes,
        "polls": core.polls,
        "transcript": simulator.transcript,
    }


def test_soak(tmp_path: Path) -> None:
    record = tmp_path / "frames.jsonl"
    result = asyncio.run(soak(record))
    frames = [json.loads(line) for line in record.read_text().splitlines()]
    transcript = [entry for entry in result["transcript"] if not entry[1].startswith(b"SIM:")]

    assert result["polls"] > 4 * VARIABLES
    assert not [n for n in result["notes"] if "polling error" in n]
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
        if "rtt_ms" not in frame:
            continue  # unsolicited or cut off: never taken as an answer
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
