"""A cell's status line: one compact badge per target, for the console and the REPL.

Each badge says one controller's state (its name in its profile's colour, the
connection, a read-only or confirm target, the round trip), so one controller down
reads as that controller down, never as the cell down. The line is made for a width:
long words first, then short ones, then shorter names, never a badge dropped.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rich.style import Style
from rich.text import Text

from ..protocol.text import terminal_safe
from .status import CANNOT_CONNECT, RUNNING_SHOWN_AFTER, RUNNING_STYLE, label_style

if TYPE_CHECKING:
    from ..engine.published.status import Status

SEPARATOR = " │ "
#: Names are cut to this many cells when the line is still too wide.
SHORT_NAME = 6


@dataclass(frozen=True, slots=True)
class Badge:
    """What one target's badge is made of (the name as typed after ``@``)."""

    name: str
    status: Status | None
    colour: str | None = None  # the profile's colour
    current: bool = False  # lines without @NAME go here


def _cut(name: str, width: int) -> str:
    return name if len(name) <= width else name[: max(1, width - 1)] + "…"


def connection_words(status: Status | None, now: float) -> tuple[Text, Text]:
    """The connection, long and short: connected, lost, a backoff's countdown,
    connecting, or why it never opened."""
    if status is None:
        return Text("starting", style="yellow"), Text("…", style="yellow")
    state = status.connection
    if status.retry_at is not None and (state in ("lost", "dropped") or state in CANNOT_CONNECT):
        wait = max(0.0, status.retry_at - now)
        word = "lost" if state in ("lost", "dropped") else CANNOT_CONNECT[state][1]
        return (
            Text(f"{word}, retry {wait:.1f}s", style="bold red"),
            Text(f"{word} {wait:.0f}s", style="bold red"),
        )
    if state in ("lost", "dropped"):
        return Text("lost", style="bold red"), Text("lost", style="bold red")
    if state == "engine stopped":
        stopped = Text("ENGINE STOPPED", style="bold white on red")
        return stopped, Text("STOPPED", style="bold white on red")
    if state in CANNOT_CONNECT:
        short = CANNOT_CONNECT[state][1]
        return Text(short, style="bold red"), Text(short, style="bold red")
    if state == "connected":
        return Text("connected", style="green"), Text("up", style="green")
    if state == "connecting":
        return Text("connecting…", style="yellow"), Text("conn…", style="yellow")
    return Text("idle", style="dim"), Text("idle", style="dim")


def _writes(status: Status | None, short: bool) -> Text | None:
    if status is None:
        return None
    if status.read_only or status.writes == "read-only":
        return Text("RO" if short else "read-only", style="bold #5f87ff")
    if status.writes == "confirm":
        return Text("ask" if short else "confirm", style="bold #af5fd7")
    return None


def _rtt(status: Status | None) -> Text | None:
    if status is None or status.rtt is None or status.connection != "connected":
        return None
    ms = status.rtt * 1000
    return Text(f"{ms:.1f}ms" if ms < 10 else f"{ms:.0f}ms", style="dim")


def badge_text(badge: Badge, form: int, now: float) -> Text:
    """One badge in form 0 (long words), 1 (short words) or 2 (short words, name cut)."""
    name = terminal_safe(badge.name)
    if form >= 2:
        name = _cut(name, SHORT_NAME)
    style = label_style(badge.colour) if badge.colour else Style(bold=True)
    text = Text()
    text.append("›" if badge.current else " ", style="bold cyan")
    text.append(f" {name} " if badge.colour else name, style=style)
    long, short = connection_words(badge.status, now)
    for part in (short if form else long, _writes(badge.status, form > 0), _rtt(badge.status)):
        if part is not None:
            text.append(" ")
            text.append_text(part)
    return text


def running_text(running: tuple[str, float, int] | None, form: int) -> Text | None:
    """The way out of a long line (``Esc cancels``), once it has run a moment; the
    line itself only in the long form."""
    if running is None or running[1] < RUNNING_SHOWN_AFTER:
        return None
    line, seconds, queued = running
    what = f" Esc cancels: {_cut(terminal_safe(line), 20)}" if form == 0 else " Esc"
    more = f" +{queued}" if queued else ""
    return Text(f"{what} ({seconds:.0f} s){more} ", style=RUNNING_STYLE)


def cell_status_text(
    badges: Sequence[Badge],
    width: int | None = None,
    now: float | None = None,
    running: tuple[str, float, int] | None = None,
) -> Text:
    """The badges side by side, in the longest form that fits ``width`` (None: the
    longest), then the running line's way out; the shortest form when none does (the
    widget crops what is left: the running line, last, goes first)."""
    when = time.monotonic() if now is None else now
    line = Text()
    for form in range(3):
        line = Text(SEPARATOR).join(badge_text(badge, form, when) for badge in badges)
        shown = running_text(running, form)
        if shown is not None:
            line = Text.assemble(line, "  ", shown)
        if width is None or line.cell_len <= width:
            break
    line.no_wrap = True
    line.overflow = "crop"
    return line
