"""Token kinds of a typed line, for input colouring (pure)."""

from __future__ import annotations

import re

from ..commands.language import is_raw_line
from ..engine.commands.builtin import BUILTIN
from ..protocol import KINDS

_WORD_RE = re.compile(r"\s+|\S+", re.ASCII)
_VAR_RE = re.compile(r"([A-Za-z]+)(\[?)(\d+(?:-\d+)?)?(\]?)", re.ASCII)


def tokenize(line: str) -> list[tuple[str, str]]:
    """(kind, text) pieces covering the line exactly.

    Kinds: ``command``, ``type``, ``index``, ``value``, ``raw``, ``error``, ``space``.
    """
    if is_raw_line(line):
        return [("raw", line)]
    pieces = _WORD_RE.findall(line)
    out: list[tuple[str, str]] = []
    position = 0  # words seen so far
    command = ""
    variable = False  # the command takes a variable
    for piece in pieces:
        if piece.isspace():
            out.append(("space", piece))
            continue
        if position == 0:
            command = piece.lower()
            spec = BUILTIN.get(command)
            variable = spec is not None and spec.takes_variable
            out.append(("command" if spec is not None else "error", piece))
        elif variable and position == 1:
            match = _VAR_RE.fullmatch(piece)
            if match and match.group(1).upper() in KINDS:
                out.append(("type", match.group(1) + match.group(2)))
                if match.group(3):
                    out.append(("index", match.group(3) + match.group(4)))
                    position += 1
            elif command == "unwatch" and piece.lower() == "all":
                out.append(("value", piece))
            else:
                out.append(("error", piece))
        elif variable and position == 2:
            out.append(("index", piece))
        else:
            out.append(("value", piece))
        position += 1
    return out
