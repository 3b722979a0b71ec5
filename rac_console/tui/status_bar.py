"""The status line: target, connection, round trip, poll cycle, badges."""

from __future__ import annotations

import time

from rich.text import Text
from textual.widgets import Static

from ..core import ConsoleCore
from ..protocol.text import terminal_safe

#: A reply is shown as awaited once it is this late (seconds): quicker ones would flicker.
WAITING_SHOWN_AFTER = 0.2


def status_text(core: ConsoleCore, frames_per_second: float) -> Text:
    text = Text()
    if core.session is None:
        style = "bold white on grey35"
    elif core.is_simulator:
        style = "bold black on yellow"
    else:
        style = "bold white on red"
    text.append(f" {terminal_safe(core.target)} ", style=style)
    # Badges that change what a command does come first: never cut off a narrow screen.
    if core.read_only:
        text.append(" ")
        text.append(" READ-ONLY ", style="bold white on blue")
    if core.record_failure is not None:
        text.append(" ")
        text.append(" RECORDING STOPPED ", style="bold white on red")
    text.append(" ")
    state = core.connection
    if state in ("lost", "dropped") and core.retry_at is not None:
        wait = max(0.0, core.retry_at - time.monotonic())
        what = "lost" if state == "lost" else "dropped early"
        text.append(f"{what}, retrying in {wait:.1f} s (backoff)", style="bold red")
    elif state == "connected":
        text.append("connected", style="green")
    elif state == "connecting":
        text.append("connecting…", style="yellow")
    else:
        text.append("idle" if core.session is not None else "disconnected", style="dim")
    session = core.session  # read once: a disconnect on the engine's thread may clear it
    connected = state == "connected" and session is not None
    rtt = session.last_rtt if connected and session is not None else None
    text.append(f" · rtt {rtt * 1000:.2f} ms" if rtt is not None else " · rtt –")
    sent_at = session.waiting_since if connected and session is not None else None
    if sent_at is not None:
        waited = time.perf_counter() - sent_at
        if waited >= WAITING_SHOWN_AFTER:
            text.append(
                f" · waiting for a reply {waited:.1f} s of {core.timeout:g} s", style="bold yellow"
            )
    if core.paused:
        text.append("  POLLING PAUSED", style="bold yellow")
    elif connected and core.watch.rows and core.cycle_seconds is not None and core.polls_per_second:
        period = core.period
        if period == 0:
            text.append(f" · cycle {core.cycle_seconds * 1000:.0f} ms back to back")
        else:
            text.append(f" · cycle {core.cycle_seconds * 1000:.0f} ms/{period:g} s")
        if not core.interval_met:
            text.append(" NOT MET", style="bold yellow")
        text.append(f" · {core.polls_per_second:.0f} polls/s")
    if frames_per_second:
        text.append(f" · {frames_per_second:.0f} frames/s", style="dim")
    return text


class StatusBar(Static):
    pass
