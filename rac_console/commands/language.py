"""The command language shared by the console, the REPL and ``run``.

``parse_command(line)`` turns one typed line into a command object or raises
:class:`InputError` with what is wrong and how to write it; nothing here sends
anything.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..protocol import InputError, Variant, VarKind, encode_request, kind_of, parse_index
from ..protocol.messages import get_request, put_request
from ..protocol.variables import encode_value


@dataclass(frozen=True)
class VarRef:
    kind: VarKind
    index: int

    def __str__(self) -> str:
        return f"{self.kind.code}{self.index}"


@dataclass(frozen=True)
class Get:
    var: VarRef

    @property
    def wire(self) -> str:
        return get_request(self.var.kind, self.var.index)


@dataclass(frozen=True)
class Put:
    var: VarRef
    value: Variant
    value_text: str

    @property
    def wire(self) -> str:
        return put_request(self.var.kind, self.var.index, self.value_text)


@dataclass(frozen=True)
class Raw:
    """A line sent exactly as typed: ``GET:...``/``PUT:...`` or ``send TEXT``."""

    wire: str


Exchange = Get | Put | Raw
Command = Exchange

_VAR_RE = re.compile(r"\s*([A-Za-z]+)(?:\[\s*([^\]]*?)\s*\]|(\d+))?")
_RAW_PREFIXES = ("GET:", "PUT:")


def is_raw_line(line: str) -> bool:
    return line.lstrip(" \t")[:4].upper() in _RAW_PREFIXES


def split_word(line: str) -> tuple[str, str]:
    """The first word (lower-cased) and the rest, leading blanks removed."""
    stripped = line.lstrip()
    word, _, rest = stripped.partition(" ")
    return word.lower(), rest


def parse_var(text: str, usage: str) -> tuple[VarRef, str]:
    """``I 10``, ``I10``, ``I[10]`` (any case) and the text after it."""
    match = _VAR_RE.match(text)
    if not match or not match.group(1):
        raise InputError(f"missing variable: {usage}")
    kind = kind_of(match.group(1))
    rest = text[match.end() :]
    index_text = match.group(2) if match.group(2) is not None else match.group(3)
    if index_text is None:
        index_match = re.match(r"\s+(\S+)", rest)
        if not index_match:
            raise InputError(f"{kind.code} needs an index: {usage}")
        index_text, rest = index_match.group(1), rest[index_match.end() :]
    return VarRef(kind, parse_index(index_text)), rest


def parse_exchange(line: str) -> Exchange | None:
    """Parse a get/put/send/raw line; None when the line is not one of those."""
    if is_raw_line(line):
        encode_request(line)
        return Raw(line)
    word, rest = split_word(line)
    if word == "send":
        if not rest:
            raise InputError("send needs the text to send: send GET:RC8:10:I:")
        encode_request(rest)
        return Raw(rest)
    if word == "get":
        var, extra = parse_var(rest, "get TYPE INDEX, e.g. get I 10 or get P[3]")
        if extra.strip():
            raise InputError(f"get takes only a variable, not {extra.strip()!r}: get {var}")
        return Get(var)
    if word == "put":
        var, value = parse_var(rest, "put TYPE INDEX VALUE..., e.g. put I 10 123")
        variant, value_text = encode_value(var.kind, value)
        command = Put(var, variant, value_text)
        encode_request(command.wire)
        return command
    return None


def parse_command(line: str) -> Command | None:
    """One line of the command language; None for a blank line or a ``#`` comment."""
    stripped = line.strip()
    if not stripped or stripped.startswith("#"):
        return None
    command = parse_exchange(line.rstrip("\r\n"))
    if command is None:
        word, _ = split_word(line)
        raise InputError(f"unknown command {word!r}: try get, put, send or a raw GET:/PUT: line")
    return command
