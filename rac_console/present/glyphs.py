"""Output that never fails on an encoding: a Windows pipe or file gets the ANSI code page
(cp1252, cp437, cp932), which has no ``→`` or ``✓``.

Chosen once per stream: a stream that can carry every glyph we print gets them as they
are; one that cannot gets all of them in ASCII forms (``->``, ``[ok]``, ``...``), so a
line never mixes the two, and anything else it cannot carry (a controller's string in
another script) is escaped as ``\\uNNNN``, never a UnicodeEncodeError after a PUT went out.
"""

from __future__ import annotations

import codecs
import contextlib
import io
import os
import sys
from typing import Any, TextIO

#: Each glyph the program prints, and its ASCII form.
ASCII_FORMS: dict[str, str] = {
    "→": "->",
    "←": "<-",
    "✓": "[ok]",
    "✗": "[x]",
    "↵": "<CR>",
    "●": "*",
    "○": "o",
    "…": "...",
    "—": "--",
    "–": "-",
    "·": "|",
    "▸": ">",
    "›": ">",
    "⚠": "!",
    "│": "|",
    "─": "-",
    "━": "-",
    "┃": "|",
}
_TABLE = str.maketrans(ASCII_FORMS)
GLYPHS = "".join(ASCII_FORMS)


def carries(encoding: str | None, text: str = GLYPHS) -> bool:
    """True when ``encoding`` can write every character of ``text``."""
    if not encoding:
        return False
    try:
        text.encode(encoding)
    except (UnicodeEncodeError, LookupError):
        return False
    return True


def ascii_forms(text: str) -> str:
    """``text`` with every glyph in its ASCII form."""
    return text.translate(_TABLE)


class AsciiText(io.TextIOWrapper):
    """A text stream whose glyphs are written in ASCII forms, and whatever else its
    encoding cannot carry escaped: for a pipe or file that cannot take our glyphs."""

    def write(self, text: str) -> int:
        super().write(text.translate(_TABLE))
        return len(text)


def safe_stream(stream: Any, force_ascii: bool = False) -> TextIO:
    """``stream`` itself when it can carry every glyph (errors escaped all the same),
    else (or with ``force_ascii``) an :class:`AsciiText` over its bytes; never raises."""
    encoding = getattr(stream, "encoding", None)
    if carries(encoding) and not force_ascii:
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None:
            with contextlib.suppress(ValueError, OSError, io.UnsupportedOperation):
                reconfigure(errors="backslashreplace")
        return stream  # type: ignore[no-any-return]
    buffer = getattr(stream, "buffer", None)
    if buffer is None or not encoding:
        return stream  # type: ignore[no-any-return]
    try:
        codecs.lookup(encoding)
        stream.flush()
    except (LookupError, ValueError, OSError):
        return stream  # type: ignore[no-any-return]
    return AsciiText(
        buffer,
        encoding=encoding,
        errors="backslashreplace",
        line_buffering=bool(getattr(stream, "line_buffering", False)),
        write_through=True,
    )


def make_streams_safe() -> None:
    """Once, at start: stdout and stderr write what they can carry (see the module), in
    ASCII forms too when ASCII is asked for (:func:`ascii_wanted`)."""
    force = ascii_wanted()
    sys.stdout = safe_stream(sys.stdout, force)
    sys.stderr = safe_stream(sys.stderr, force)


#: On a screen every glyph keeps its one cell: the ASCII form of each is one character.
_SCREEN_GLYPHS = {
    "→": ">",
    "←": "<",
    "↑": "^",
    "↓": "v",
    "✓": "+",
    "✗": "x",
    "↵": "$",
    "●": "*",
    "○": "o",
    "…": ".",
    "—": "-",
    "–": "-",
    "·": ".",
    "▸": ">",
    "▶": ">",
    "◀": "<",
    "▲": "^",
    "▼": "v",
    "›": ">",
    "⚠": "!",
}


def _screen_table() -> dict[int, str]:
    """Box drawing as ``-``, ``|`` and ``+``, block elements (scroll bars, sparklines)
    as ``_ - = #`` by height, and the glyphs above: one cell each."""
    import unicodedata

    table = {ord(k): v for k, v in _SCREEN_GLYPHS.items()}
    for code in range(0x2500, 0x2580):  # box drawing
        name = unicodedata.name(chr(code), "")
        if "HORIZONTAL" in name and "VERTICAL" not in name:
            table[code] = "-"
        elif "VERTICAL" in name and "HORIZONTAL" not in name:
            table[code] = "|"
        else:
            table[code] = "+"
    for code, form in zip(range(0x2581, 0x2589), "__--==##", strict=True):  # ▁ to █
        table[code] = form
    for code in range(0x2589, 0x25A0):  # left blocks, shades, quadrants
        table.setdefault(code, "#")
    table[0x2580] = "#"
    return table


SCREEN_TABLE = _screen_table()


def ascii_wanted(environ: dict[str, str] | None = None, platform: str = sys.platform) -> bool:
    """ASCII on screen: asked for (``RAC_CONSOLE_ASCII=1``, or ``0`` to refuse it), or
    Windows' old console host (conhost, no ``WT_SESSION``), whose fonts lack ``↵ ● →``."""
    env = os.environ if environ is None else environ
    asked = env.get("RAC_CONSOLE_ASCII", "").strip().lower()
    if asked in ("1", "true", "yes", "on"):
        return True
    if asked in ("0", "false", "no", "off"):
        return False
    return platform == "win32" and not env.get("WT_SESSION") and not env.get("TERM_PROGRAM")
