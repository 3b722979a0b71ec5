"""Data the tests share: the vendor's sample exchanges and statuses to present."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

from rac_console.engine import Status

#: ``rac-samples.json``: the vendor's requests and responses, by kind (``get``, ``put``).
SAMPLES: dict[str, Any] = json.loads(
    (Path(__file__).parent.parent / "rac-samples.json").read_text(encoding="utf-8")
)
#: The sample GETs: the request line (no CR) to its response (no CR).
GET_SAMPLES: dict[bytes, bytes] = {
    s["request"].encode("ascii"): s["response"].encode("ascii") for s in SAMPLES["get"]
}

#: The status of the built-in simulator, connected.
SIM = Status(
    target="SIMULATOR (built-in)",
    is_simulator=True,
    has_session=True,
    host="127.0.0.1",
    port=40000,
    timeout=2.0,
    read_only=False,
    connection="connected",
    retry_at=None,
    rtt=0.00025,
    paused=False,
    watched=0,
    interval=0.5,
    period=0.5,
    cycle_seconds=None,
    polls_per_second=None,
    interval_met=True,
    record_failure=None,
    seen=frozenset(),
)
#: A live target by its profile: a label, a colour, writes that ask first.
CELL3 = replace(
    SIM,
    target="LIVE 192.168.0.1:5006",
    is_simulator=False,
    host="192.168.0.1",
    port=5006,
    profile="cell3",
    label="Cell 3 — welding",
    colour="red",
    writes="confirm",
)
