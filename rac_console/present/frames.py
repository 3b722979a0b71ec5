"""One line per frame for the console's log and the REPL's ``frames on``."""

from __future__ import annotations

import time
from functools import lru_cache
from typing import TYPE_CHECKING

from ..protocol.text import describe_response, terminal_safe, wire_text

if TYPE_CHECKING:
    from ..session import Frame

ARROWS = {"tx": "→", "rx": "←"}


@lru_cache(maxsize=4)
def _seconds_text(second: int) -> str:
    return time.strftime("%H:%M:%S", time.localtime(second))


def clock_text(timestamp: float) -> str:
    """``14:03:07.123``: local time with milliseconds."""
    return f"{_seconds_text(int(timestamp))}.{int(timestamp % 1 * 1000):03d}"


def decoding(frame: Frame) -> str:
    """A reply's short decoding: ``S_OK  VT_I4  123``, the HRESULT, or why it is garbled.

    A reply to a request comes parsed by the session; only a line nobody asked for
    is parsed here."""
    if frame.response is not None:
        described = describe_response(frame.response)
        return described if frame.problem is None else f"{described}  REFUSED: {frame.problem}"
    if frame.problem is not None:
        return f"garbled: {frame.problem}"
    return _decode(frame.data[:-1] if frame.data.endswith(b"\r") else frame.data)


@lru_cache(maxsize=4096)
def _decode(body: bytes) -> str:
    """Cached: polled replies repeat, and the log decodes thousands a second. (Replies
    come parsed: only a line nobody asked for is parsed here, so the parser loads late.)"""
    from ..protocol.errors import ProtocolError
    from ..protocol.messages import decode_frame, parse_response

    try:
        return describe_response(parse_response(decode_frame(body)))
    except ProtocolError as exc:
        return f"garbled: {exc}"
    except Exception as exc:  # the log must show every frame, whatever it holds
        return f"undecodable: {exc!r}"


#: Columns of :func:`gap_text` (a gap of 1000 s or more takes more).
GAP_WIDTH = 7


def gap_text(seconds: float | None) -> str:
    """The time since the previous frame, its unit chosen so the figure stays short:
    `` +0.21ms``, ``+12.3ms``, `` +500ms``, ``+1.500s``, ``+12.50s``; blank for the first.

    Each form is used while its rounding stays in range (9.996 ms is ``+10.0ms``, not
    ``+10.00ms``): the bounds are where the next digit would round up. On every line the
    log draws, so plain comparisons, no ``round``."""
    if seconds is None:
        return " " * GAP_WIDTH
    ms = seconds * 1000 if seconds > 0 else 0.0
    if ms < 9.995:
        return f"+{ms:.2f}ms"
    if ms < 99.95:
        return f"+{ms:.1f}ms"
    if ms < 999.5:
        return f" +{ms:.0f}ms"
    if ms < 9_999.5:
        return f"+{seconds:.3f}s"
    if ms < 99_995:
        return f"+{seconds:.2f}s"
    if ms < 999_950:
        return f"+{seconds:.1f}s"
    return f"{f'+{seconds:.0f}s':>{GAP_WIDTH}}"


def hex_text(data: bytes) -> str:
    """Every byte of a frame in hex, CR included: ``47 45 54 3a … 0d``."""
    return data.hex(" ")


def frame_line(frame: Frame) -> str:
    """``14:03:07.123 ← 0,3,123↵   0.21 ms  S_OK  VT_I4  123``."""
    return f"{clock_text(frame.time)} {frame_body(frame)}"


def frame_body(frame: Frame) -> str:
    """A frame line after its time: ``← 0,3,123↵   0.21 ms  S_OK  VT_I4  123``."""
    line = f"{ARROWS[frame.direction]} {wire_text(frame.data)}"
    if frame.source is not None:  # another client of the agent asked: said whose
        line = f"{line}   [{terminal_safe(frame.source)}]"
    if frame.direction == "tx":
        return line
    notes = []
    if frame.rtt is not None:
        notes.append(f"{frame.rtt * 1000:.2f} ms")
    if frame.unsolicited:
        notes.append("UNSOLICITED (connection reset)")
    if not frame.data.endswith(b"\r"):
        notes.append("INCOMPLETE (connection closed)")
    else:
        notes.append(decoding(frame))
    return line + "   " + "  ".join(notes)


#: Where the hex view puts each frame's bytes, by what the log drew last.
HEX_PLACES = {
    "beside": "beside its text, in one column",
    "under": "on lines under its text (wider terminals put them beside)",
    "mixed": "beside its text, or under it when the line is too long",
    "none": "beside its text, or under it when both do not fit",
}


def hex_view_said(shown: bool, placement: str) -> str:
    """What F7 says: where the bytes go now, or that they are hidden."""
    return (
        f"hex view: each frame's bytes {HEX_PLACES[placement]} (F7 hides them)"
        if shown
        else "hex view off"
    )


def frame_times_said(shown: bool) -> str:
    if shown:
        return "frame times: the time since the previous frame on each line"
    return "frame times hidden (t in the frame log shows them)"


def poll_frames_said(shown: bool) -> str:
    if shown:
        return "poll frames shown"
    return "poll frames hidden (typed commands only; F3 shows them)"
