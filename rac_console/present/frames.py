"""One line per frame for the console's log and the REPL's ``frames on``."""

from __future__ import annotations

import time
from functools import lru_cache

from ..protocol import ProtocolError, decode_frame, parse_response, wire_text
from ..protocol.text import describe_response
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
    """Cached: polled replies repeat, and the log decodes thousands a second."""
    try:
        return describe_response(parse_response(decode_frame(body)))
    except ProtocolError as exc:
        return f"garbled: {exc}"
    except Exception as exc:  # the log must show every frame, whatever it holds
        return f"undecodable: {exc!r}"


def frame_line(frame: Frame) -> str:
    """``14:03:07.123 ← 0,3,123↵   0.21 ms  S_OK  VT_I4  123``."""
    line = f"{clock_text(frame.time)} {ARROWS[frame.direction]} {wire_text(frame.data)}"
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
