"""How the frame log's lines look: each frame's bytes beside its text or under it (the
hex view's layout), and the styles put on the lines on screen as they are drawn.

Pure functions of the lines' lengths and the log's width: the log (:mod:`.frame_log`)
keeps the frames and decides when to draw; this module decides where things go.
"""

from __future__ import annotations

import math
import re

from rich.cells import cell_len
from rich.highlighter import Highlighter
from rich.text import Text

#: Between a frame's text and its bytes in hex, when both fit the width.
HEX_SEPARATOR = "  │ "
#: A gap before a reply at least this long (the app sets half the timeout) stands out.
SLOW_STYLE = "bold black on yellow"

#: A frame as the layout weighs it: the length of its line, and of its bytes in hex.
Sizes = list[tuple[int, int]]


def hex_fits(width: int, line: str, hexed: str) -> bool:
    """Whether the bytes fit beside the line (any width fits before the first layout)."""
    return not width or len(line) + len(HEX_SEPARATOR) + len(hexed) <= width


def hex_plan(frames: Sizes, width: int) -> int | None:
    """Where these frames' bytes go at this width: the column beside their text (the
    longest text of the frames whose bytes could fit beside it), when every such frame
    fits at that column; else None: under every frame's text, so requests and replies
    are never laid out two ways. A frame too long for its bytes beside it at any column
    has them under it either way."""
    if not width:
        return 0  # not laid out yet: drawn again at the first size
    fits = [(text, hexed) for text, hexed in frames if text + len(HEX_SEPARATOR) + hexed <= width]
    column = max((text for text, _ in fits), default=0)
    if all(column + len(HEX_SEPARATOR) + hexed <= width for _, hexed in fits):
        return column
    return None


def hex_moves(frames: Sizes, column: int | None, width: int) -> bool:
    """True when these new frames change where the bytes go at ``column``."""
    if column is None:
        return False  # every frame's bytes under it: more frames cannot change that
    for text, hexed in frames:
        if text + len(HEX_SEPARATOR) + hexed > width:
            continue  # under it, wherever the others are
        if text > column or column + len(HEX_SEPARATOR) + hexed > width:
            return True
    return False


def hex_under(hexed: str, indent: int, width: int) -> list[str]:
    """A frame's hex on lines of their own under it, from its arrow's column."""
    per_line = max(4, (width - indent + 1) // 3)
    pairs = hexed.split(" ")
    pad = " " * indent
    return [pad + " ".join(pairs[at : at + per_line]) for at in range(0, len(pairs), per_line)]


#: Characters of a frame line that are one cell wide though not ASCII.
_NARROW = frozenset("→←↵─│ ·") | frozenset(chr(c) for c in range(32, 127))


def lines_width(lines: list[str]) -> int:
    """Frame lines are ASCII but for the arrows, so their length is their width; only
    another line is measured (thousands of lines a second)."""
    return max(
        len(line) if line.isascii() or _NARROW.issuperset(line) else cell_len(line)
        for line in lines
    )


#: A frame line's start: the time, the gap (when shown), the arrow.
_HEAD = re.compile(r"\d\d:\d\d:\d\d\.\d{3} +(?:(\+\d+(?:\.\d+)?)(ms|s) )?(?:\S+ +)?([→←]) ")
#: A line of hex under its frame.
_HEX_LINE = re.compile(r" +[0-9a-f]{2}(?: [0-9a-f]{2})*$")


class FrameHighlighter(Highlighter):
    """Styles a frame line as it is drawn (the lines on screen only): the gap dim, or
    highlighted before a reply that took :attr:`slow_after` seconds or more; the hex dim."""

    def __init__(self) -> None:
        self.slow_after = math.inf

    def highlight(self, text: Text) -> None:
        plain = text.plain
        head = _HEAD.match(plain)
        if head is None:
            if _HEX_LINE.match(plain):
                text.stylize("dim")
            return
        number, unit, arrow = head.groups()
        if number is not None:
            seconds = float(number[1:]) / (1000 if unit == "ms" else 1)
            slow = arrow == "←" and seconds >= self.slow_after
            text.stylize(SLOW_STYLE if slow else "dim", head.start(1), head.end(2))
        at = plain.rfind(HEX_SEPARATOR)
        if at >= 0:
            text.stylize("dim", at)
