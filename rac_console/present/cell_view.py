"""How a cell is shown by every front end: each target's badge, results named by
their target, and the targets completion offers.

A badge says one controller's state on its own, so one controller down never looks
like the cell down: ``cell3 ok 0.4ms``, ``cell4 LOST``, ``cell5 retry 3s``,
``cell3 ok RO`` (read-only) or ``CONFIRM``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from rich.text import Text

from ..engine.cell import Cell
from ..engine.events import Status
from ..protocol.text import terminal_safe


@dataclass(frozen=True)
class Badge:
    """One target's state in a few characters; ``ok``: connected and answering."""

    text: str
    ok: bool


def target_badge(name: str, status: Status | None, now: float | None = None) -> Badge:
    """``NAME STATE [RTT] [RO|CONFIRM]`` for a cell's status line or toolbar."""
    shown = terminal_safe(name)
    if status is None:
        return Badge(f"{shown} starting", False)
    connection = status.connection
    if connection == "connected":
        rtt = f" {status.rtt * 1000:.1f}ms" if status.rtt is not None else ""
        state, ok = f"ok{rtt}", True
    elif status.retry_at is not None:
        wait = max(0.0, status.retry_at - (time.monotonic() if now is None else now))
        state, ok = f"retry {wait:.0f}s", False
    elif connection in ("lost", "dropped") or status.ever_connected:
        state, ok = "LOST", False
    elif connection == "connecting":
        state, ok = "connecting", False
    else:
        state, ok = "DOWN", False
    rules = (
        " RO" if status.writes == "read-only" else " CONFIRM" if status.writes == "confirm" else ""
    )
    if status.paused:
        rules += " paused"
    return Badge(f"{shown} {state}{rules}", ok)


def by_target(name: str | None, text: Text) -> Text:
    """``text`` led by its target's name (``cell4 › ...``), when several are open."""
    if name is None:
        return text
    return Text.assemble((terminal_safe(name), "bold"), " › ", text)


def cell_targets(cell: Cell) -> list[tuple[str, str]]:
    """What ``use`` and ``@`` complete to: each open target, with its label or address
    as the candidate's help; none for a single target."""
    if cell.single:
        return []
    return [
        (
            member.name,
            terminal_safe(member.target.label or f"{member.target.host}:{member.target.port}"),
        )
        for member in cell.members
    ]
