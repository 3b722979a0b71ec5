"""What a pane's filter (``/``) matches, and how its border says so: shared by the watch
table (rows by name or label) and the frame log (frames by text or by variable)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rich.text import Text

from ..protocol.errors import InputError
from ..protocol.text import counted, terminal_safe

if TYPE_CHECKING:
    from ..protocol.request import RequestLine


def needle_of(typed: str) -> str:
    """The text a filter looks for: as typed, without the blanks around it, any case."""
    return typed.strip().lower()


def add_filter_title(title: Text, typed: str) -> None:
    """`` filter "io13"`` on a border title: the filter as typed, made safe, in bold."""
    title.append("  filter ")
    title.append(f'"{terminal_safe(typed.strip())}"', style="bold")


@dataclass(frozen=True, slots=True)
class FrameFilter:
    """The frame log's filter: a variable (``IO128``, ``I 10``, ``P[3]``) keeps the frames
    that get or put it and their replies; any other text keeps the lines that hold it.
    In a cell, a first word ``@NAME`` (or ``/NAME``) keeps one target's frames: alone
    (``@robotA``) or before the rest (``@robotB IO64``)."""

    typed: str = ""
    needle: str = ""
    var: tuple[str, int] | None = None
    target: str | None = None  # a cell's target, as named after @

    @classmethod
    def of(cls, typed: str) -> FrameFilter:
        from ..commands.language import parse_var  # the grammar, at the first filter typed

        target = None
        text = typed.strip()
        if text[:1] in ("@", "/") and len(text) > 1:
            first, _, text = text.partition(" ")
            target = first[1:]
        needle = needle_of(text)
        var = None
        try:
            ref, rest = parse_var(text.strip(), "")
        except InputError:
            pass
        else:
            if not rest.strip():
                var = (ref.kind.code, ref.index)
        return cls(typed, needle, var, target)

    def __bool__(self) -> bool:
        return bool(self.needle) or self.target is not None

    def matches(self, request: RequestLine | None, body: str, target: str | None = None) -> bool:
        """``request``: the frame's (a reply's is the request it answered, None when it
        answered nothing); ``body``: the line as shown, after its time; ``target``: the
        cell's target the frame went to or came from."""
        if self.target is not None and (target is None or target.lower() != self.target.lower()):
            return False
        if not self.needle:
            return True
        if self.var is not None:
            return request is not None and request.names(*self.var)
        return self.needle in body.lower()


TITLE = "Frames (→ sent, ← received)"
FROZEN_TITLE = "Frames (FROZEN: F4 follows)"


def log_title(
    frozen: bool, hex_view: bool, typed: str, polls: bool, shown: tuple[int, int]
) -> Text:
    """The frame log's border title: frozen or following, the hex view, the filter as
    typed and how many frames pass it (``shown`` of kept), whether polls are hidden."""
    title = Text(FROZEN_TITLE if frozen else TITLE)
    if hex_view:
        title.append("  hex")
    if typed:
        add_filter_title(title, typed)
    if typed or not polls:
        title.append(f"  {shown[0]} of {counted(shown[1], 'frame')}")
    if not polls:
        title.append("  polls hidden (F3)")
    return title
