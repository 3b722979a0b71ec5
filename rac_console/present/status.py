"""The status line: target, connection, round trip, poll cycle, badges."""

from __future__ import annotations

import time

from rich.text import Text

from ..engine.events import Status
from ..protocol.text import terminal_safe

#: A reply is shown as awaited once it is this late (seconds): quicker ones would flicker.
WAITING_SHOWN_AFTER = 0.2
#: A typed line is shown as running once it has run this long (seconds).
RUNNING_SHOWN_AFTER = 0.5
#: Characters of a running line shown.
RUNNING_WIDTH = 24


def status_text(
    status: Status,
    waiting_since: float | None,
    frames_per_second: float,
    running: tuple[str, float, int] | None = None,
) -> Text:
    """The line for ``status``; ``waiting_since`` is when the request in flight left
    (``time.perf_counter()``), from the outbox; ``running``: the typed line running for
    how many seconds, and how many lines wait behind it."""
    text = Text()
    if not status.has_session:
        style = "bold white on grey35"
    elif status.is_simulator:
        style = "bold black on yellow"
    else:
        style = "bold white on red"
    text.append(f" {terminal_safe(status.target)} ", style=style)
    # Badges that change what a command does come first: never cut off a narrow screen.
    if status.read_only:
        text.append(" ")
        text.append(" READ-ONLY ", style="bold white on blue")
    if status.record_failure is not None:
        text.append(" ")
        text.append(" RECORDING STOPPED ", style="bold white on red")
    if status.csv_log is not None:  # a new log runs: an earlier failure is for the exit
        text.append(" ")
        text.append(" CSV ", style="bold black on green")
    elif status.csv_failure is not None:
        text.append(" ")
        text.append(" CSV LOG STOPPED ", style="bold white on red")
    if running is not None and running[1] >= RUNNING_SHOWN_AFTER:
        # Before the figures: on 80 columns the way out must not be cut off.
        line, seconds, queued = running
        shown = line if len(line) <= RUNNING_WIDTH else line[: RUNNING_WIDTH - 1] + "…"
        text.append(" ")
        text.append(
            f" Esc cancels: {terminal_safe(shown)} ({seconds:.0f} s) ", style="bold black on yellow"
        )
        if queued:
            text.append(f" +{queued} queued", style="bold yellow")
    text.append(" ")
    state = status.connection
    if state in ("lost", "dropped") and status.retry_at is not None:
        wait = max(0.0, status.retry_at - time.monotonic())
        what = "lost" if state == "lost" else "dropped early"
        text.append(f"{what}, retrying in {wait:.1f} s (backoff)", style="bold red")
    elif state == "connected":
        text.append("connected", style="green")
    elif state == "connecting":
        text.append("connecting…", style="yellow")
    else:
        text.append("idle" if status.has_session else "disconnected", style="dim")
    connected = state == "connected" and status.has_session
    rtt = status.rtt if connected else None
    text.append(f" · rtt {rtt * 1000:.2f} ms" if rtt is not None else " · rtt –")
    if connected and waiting_since is not None:
        waited = time.perf_counter() - waiting_since
        if waited >= WAITING_SHOWN_AFTER:
            text.append(
                f" · waiting for a reply {waited:.1f} s of {status.timeout:g} s",
                style="bold yellow",
            )
    if status.paused:
        text.append("  POLLING PAUSED", style="bold yellow")
    elif (
        connected
        and status.watched
        and status.cycle_seconds is not None
        and status.polls_per_second
    ):
        period = status.period
        if period == 0:
            text.append(f" · cycle {status.cycle_seconds * 1000:.0f} ms back to back")
        else:
            text.append(f" · cycle {status.cycle_seconds * 1000:.0f} ms/{period:g} s")
        if not status.interval_met:
            text.append(" NOT MET", style="bold yellow")
        text.append(f" · {status.polls_per_second:.0f} polls/s")
    if frames_per_second:
        text.append(f" · {frames_per_second:.0f} frames/s", style="dim")
    return text
