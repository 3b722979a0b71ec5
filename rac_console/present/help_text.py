"""The help's text: keys, commands and the status line's figures, in sections.

Shared by the front ends (the console's help screen; the REPL's ``help`` can read it
too). Nothing here is written twice: the commands come from the registry, the keys
from the bindings a front end passes in as ``(key, description)`` pairs; only what
the status line's figures mean is written here, beside :mod:`.status` which draws them.

Plain strings only: a front end styles them (as Rich ``Text``, never markup).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class HelpEntry:
    """One thing explained: a key, a command's usage or a figure, and what it means."""

    term: str
    text: str
    more: tuple[str, ...] = ()  # further lines: an example, notes

    def matches(self, folded_query: str) -> bool:
        """Whether the case-folded query occurs in any of its lines."""
        return any(folded_query in line.casefold() for line in (self.term, self.text, *self.more))


@dataclass(frozen=True)
class HelpSection:
    title: str
    entries: tuple[HelpEntry, ...]


KeyGroup = tuple[str, Sequence[tuple[str, str]]]  # ("watch table", [("Space", "Toggle"), ...])

#: Key names as printed on the keyboard.
_KEY_NAMES = {
    "escape": "Esc",
    "slash": "/",
    "question_mark": "?",
    "space": "Space",
    "delete": "Delete",
    "enter": "Enter",
    "tab": "Tab",
    "backspace": "Backspace",
    "pageup": "PgUp",
    "pagedown": "PgDn",
    "home": "Home",
    "end": "End",
    "up": "Up",
    "down": "Down",
    "left": "Left",
    "right": "Right",
    "ctrl": "Ctrl",
    "shift": "Shift",
    "alt": "Alt",
}


def key_label(key: str) -> str:
    """``ctrl+l`` → ``Ctrl+L``, ``f2`` → ``F2``, ``escape`` → ``Esc``, ``s`` → ``s``."""
    parts = key.split("+")
    *modifiers, last = parts
    function_key = len(last) > 1 and last[0] == "f" and last[1:].isdigit()
    if last in _KEY_NAMES:
        name = _KEY_NAMES[last]
    elif function_key or (modifiers and len(last) == 1):
        name = last.upper()  # F2, Ctrl+L
    else:
        name = last
    return "+".join([*(_KEY_NAMES.get(m, m.title()) for m in modifiers), name])


def key_entries(bindings: Iterable[tuple[str, str]]) -> tuple[HelpEntry, ...]:
    """``(key, description)`` pairs as entries, in order; keys that do the same thing
    (the same description) share one entry: ``t / Esc  Close trend``."""
    keys: dict[str, list[str]] = {}
    for key, description in bindings:
        if not description:
            continue
        label = key_label(key)
        shared = keys.setdefault(description, [])
        if label not in shared:
            shared.append(label)
    return tuple(
        HelpEntry(("" if set(labels) <= _ARROWS else " / ").join(labels), text)
        for text, labels in keys.items()
    )


#: Keys shown side by side, with no slash between them: ``←→↑↓``.
_ARROWS = frozenset("←→↑↓")


def command_entries() -> tuple[HelpEntry, ...]:
    """Every command of the registry: usage, summary, example and notes."""
    from ..engine.commands.builtin import BUILTIN
    from ..engine.commands.registry import RAW_HELP

    entries = [
        HelpEntry(
            spec.usage,
            spec.summary,
            ((f"e.g. {spec.example}",) if spec.example else ()) + spec.notes,
        )
        for spec in BUILTIN
    ]
    entries.append(HelpEntry("GET:... PUT:...", RAW_HELP))
    return tuple(entries)


#: What each figure of the status line (:func:`.status.status_text`) means, left to right.
STATUS_FIGURES: tuple[HelpEntry, ...] = (
    HelpEntry(
        " Cell 3 — welding ",
        "first, with a target profile (-H NAME, connect NAME): its label (or name) in "
        "the profile's colour, so two consoles on two robots cannot be mixed up",
    ),
    HelpEntry(
        " SIMULATOR (built-in) ",
        "the target: the simulator built into rac-console, on yellow; writes are open",
    ),
    HelpEntry(" LIVE host:port ", "the target: a real controller, on red"),
    HelpEntry(" NOT CONNECTED ", "no session (after disconnect); connect HOST opens one"),
    HelpEntry(
        " READ-ONLY ",
        "writes are refused before anything is sent (--read-only, or a profile's "
        'writes = "read-only")',
    ),
    HelpEntry(
        " CONFIRM WRITES ",
        'a profile\'s writes = "confirm": each write asks old → new first, default No',
    ),
    HelpEntry(
        "writes open",
        'writes go out as typed (the simulator, or a profile\'s writes = "open"); a '
        "profile's allow = [...] still refuses writes outside its ranges",
    ),
    HelpEntry(
        " RECORDING STOPPED ",
        "--record could not write its file: frames are no longer kept; exit status 4",
    ),
    HelpEntry(" CSV ", "a CSV log is being written (log FILE.csv; log stop ends it)"),
    HelpEntry(" CSV LOG STOPPED ", "the CSV log could not be written; exit status 4"),
    HelpEntry(" MQTT ", "the watched values are published to a broker (publish; publish off)"),
    HelpEntry(
        " MQTT LOST ",
        "the broker went away (or NO BROKER: nothing answers MQTT there; REFUSED: it "
        "refused us; BROKEN: it broke the protocol and was dropped; TLS: no TLS handshake "
        "or a certificate that does not verify): polling goes on, the latest values go "
        "out when it is back",
    ),
    HelpEntry(
        " Esc cancels: LINE (N s) ",
        "a typed line has run for over half a second (a wait, a latency run, a slow "
        "reply): Esc on the command line cancels it; +N queued: lines typed behind it, "
        "not run if it is cancelled",
    ),
    HelpEntry("connected", "the session to the target is open"),
    HelpEntry("connecting…", "opening the session"),
    HelpEntry(
        "lost, retrying in N s (backoff)",
        "the connection broke; the next try is in N s, each wait longer than the last",
    ),
    HelpEntry(
        "dropped early, retrying in N s",
        "the controller closed a new connection at once; retried with backoff",
    ),
    HelpEntry("idle", "no connection open and none needed; the next request connects"),
    HelpEntry("disconnected", "no session (disconnect); nothing is polled"),
    HelpEntry(
        "rtt 0.31 ms",
        "the round-trip time of the last request on this connection (– when not connected)",
    ),
    HelpEntry(
        "waiting for a reply 1.4 s of 2 s",
        "a request is late (shown after 0.2 s): how long it has waited, and its timeout",
    ),
    HelpEntry(
        "cycle 12 ms/0.5 s",
        "while variables are watched: the time one poll cycle of them all takes, "
        "against the interval (interval SECONDS sets it)",
    ),
    HelpEntry(
        "NOT MET",
        "the watched variables cannot all be polled within one interval: watch fewer, "
        "or set a longer interval",
    ),
    HelpEntry("cycle 12 ms back to back", "interval 0: each cycle starts when the last ends"),
    HelpEntry("120 polls/s", "watched variables read per second, over the last 2 s"),
    HelpEntry("40 frames/s", "frames (sent and received) added to the frame log per second"),
    HelpEntry("POLLING PAUSED", "nothing is polled: F2 or resume starts polling again"),
)


#: What a frame log line shows, left to right, and where frames are kept.
FRAME_LOG_COLUMNS: tuple[HelpEntry, ...] = (
    HelpEntry("14:03:07.123", "when the frame crossed the wire (local time, milliseconds)"),
    HelpEntry(
        "+12ms",
        "the gap column: the time since the previous frame on the wire; a reply that "
        "took half the timeout or more is highlighted (t in the frame log hides the gaps)",
    ),
    HelpEntry("→ ←", "sent to the controller, received from it; ↵ is the frame's CR"),
    HelpEntry(
        "0.21 ms  S_OK  VT_I4",
        "after a reply: its round-trip time, its result code and the value's type",
    ),
    HelpEntry(
        "│ 47 45 54 …",
        "the hex view (F7): every byte of the frame, beside its text in one column, or "
        "on lines under it when the terminal is too narrow",
    ),
    HelpEntry(
        "--log FILE",
        "start option: append every frame to FILE as a plain timestamped transcript",
    ),
    HelpEntry(
        "--record FILE",
        "start option: append every frame to FILE as JSON lines (replay reads them)",
    ),
)


def help_sections(key_groups: Sequence[KeyGroup]) -> list[HelpSection]:
    """The help: a ``Keys: GROUP`` section per group of keys, then the commands, the
    frame log's columns and the status line."""
    sections = [
        HelpSection(f"Keys: {group}", key_entries(bindings)) for group, bindings in key_groups
    ]
    sections.append(HelpSection("Commands", command_entries()))
    sections.append(HelpSection("Frame log: a line, left to right", FRAME_LOG_COLUMNS))
    sections.append(HelpSection("Status line", STATUS_FIGURES))
    return sections


def filter_sections(
    sections: Sequence[HelpSection], query: str
) -> tuple[list[HelpSection], int, int]:
    """The sections cut to the entries where ``query`` occurs (case-insensitive; a
    section with none left goes; a section whose title holds it stays whole), how
    many entries are shown, and how many there are."""
    total = sum(len(section.entries) for section in sections)
    folded = query.strip().casefold()
    if not folded:
        return list(sections), total, total
    shown = []
    for section in sections:
        if folded in section.title.casefold():
            shown.append(section)
            continue
        entries = tuple(entry for entry in section.entries if entry.matches(folded))
        if entries:
            shown.append(HelpSection(section.title, entries))
    return shown, sum(len(section.entries) for section in shown), total


def plain_lines(sections: Iterable[HelpSection]) -> list[str]:
    """The help as plain lines (for a REPL, a pager, a test)."""
    lines: list[str] = []
    for section in sections:
        if lines:
            lines.append("")
        lines.append(section.title)
        width = min(24, max((len(entry.term) for entry in section.entries), default=0))
        for entry in section.entries:
            if len(entry.term) <= width:
                lines.append(f"  {entry.term:<{width}}  {entry.text}")
            else:
                lines.append(f"  {entry.term}")
                lines.append(f"  {'':<{width}}  {entry.text}")
            lines.extend(f"  {'':<{width}}    {more}" for more in entry.more)
    return lines
