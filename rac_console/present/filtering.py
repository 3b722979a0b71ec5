"""What a pane's filter (``/``) matches, and how its border says so: shared by the watch
table (rows by name or label) and the frame log (frames by text or by variable)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

from rich.text import Text

from ..commands.language import parse_var
from ..protocol import KINDS, InputError
from ..protocol.text import terminal_safe


def needle_of(typed: str) -> str:
    """The text a filter looks for: as typed, without the blanks around it, any case."""
    return typed.strip().lower()


def add_filter_title(title: Text, typed: str) -> None:
    """`` filter "io13"`` on a border title: the filter as typed, made safe, in bold."""
    title.append("  filter ")
    title.append(f'"{terminal_safe(typed.strip())}"', style="bold")


#: ``GET:RC8:<index>:<type>:`` or ``PUT:RC8:<index>:<type>:<value>``, as sent (any case).
_REQUEST_RE = re.compile(rb"(?:GET|PUT):RC8:(\d{1,5}):([A-Za-z]+):", re.IGNORECASE)


@lru_cache(maxsize=4096)
def request_var(data: bytes) -> tuple[str, int] | None:
    """The variable a request gets or puts (``("IO", 128)``), None for any other frame.

    Cached: the poller sends the same few requests thousands of times."""
    match = _REQUEST_RE.match(data)
    code = match.group(2).decode("ascii").upper() if match is not None else ""
    return (code, int(match.group(1))) if match is not None and code in KINDS else None


@dataclass(frozen=True, slots=True)
class FrameFilter:
    """The frame log's filter: a variable (``IO128``, ``I 10``, ``P[3]``) keeps the frames
    that get or put it and their replies; any other text keeps the lines that hold it."""

    typed: str = ""
    needle: str = ""
    var: tuple[str, int] | None = None

    @classmethod
    def of(cls, typed: str) -> FrameFilter:
        needle = needle_of(typed)
        var = None
        try:
            ref, rest = parse_var(typed.strip(), "")
        except InputError:
            pass
        else:
            if not rest.strip():
                var = (ref.kind.code, ref.index)
        return cls(typed, needle, var)

    def __bool__(self) -> bool:
        return bool(self.needle)

    def matches(self, request: bytes | None, body: str) -> bool:
        """``request``: the frame's own bytes for a request, its request's for a reply
        (None when it answered nothing); ``body``: the line as shown, after its time."""
        if not self.needle:
            return True
        if self.var is not None:
            return request is not None and request_var(request) == self.var
        return self.needle in body.lower()
