"""The parsers of the exchanges, the commands that are one request: ``get``, ``put``,
``send`` and a raw ``GET:``/``PUT:`` line. Their command objects (:class:`Get`,
:class:`Put`, :class:`Raw`) are the language's, beside every other command's."""

from __future__ import annotations

from collections.abc import Callable

from ..protocol import InputError
from ..protocol.variables import encode_value
from .language import Exchange, Get, Put, Raw, is_raw_line, parse_var, split_word


def parse_exchange(line: str) -> Exchange | None:
    """Parse a get/put/send/raw line; None when the line is not one of those."""
    if is_raw_line(line):
        return Raw.of(line)
    word, rest = split_word(line)
    parse = _EXCHANGES.get(word)
    return parse(rest) if parse is not None else None


def parse_send(rest: str) -> Raw:
    if not rest:
        raise InputError("send needs the text to send: send GET:RC8:10:I:")
    return Raw.of(rest)


def parse_get(rest: str) -> Get:
    var, extra = parse_var(rest, "get TYPE INDEX, e.g. get I 10 or get P[3]")
    if extra.strip():
        raise InputError(f"get takes only a variable, not {extra.strip()!r}: get {var}")
    return Get(var)


def parse_put(rest: str) -> Put:
    var, value = parse_var(rest, "put TYPE INDEX VALUE..., e.g. put I 10 123")
    variant, value_text = encode_value(var.kind, value)
    return Put.of(var, variant, value_text)


_EXCHANGES: dict[str, Callable[[str], Exchange]] = {
    "get": parse_get,
    "put": parse_put,
    "send": parse_send,
}
