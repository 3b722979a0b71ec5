"""Python values to the console's commands, and the controller's answers to Python values.

A value to write becomes the words a one-shot ``rac-console put`` takes and is parsed by
that parser (:func:`~rac_console.commands.argv.exchange_from_words`): what it refuses, and
how it says so, are the console's. Only the Python type is checked here, since the
console never sees one: a ``bool`` is no I, a ``str`` no F.
"""

from __future__ import annotations

from collections.abc import Sequence
from decimal import Decimal
from numbers import Real
from typing import Any

from ..commands.argv import exchange_from_words
from ..commands.language import Put, VarRef
from ..protocol import InputError, Variant, VarKind, kind_of, parse_index
from .errors import Refused
from .results import Value


def variable(kind: str, index: int) -> VarRef:
    """``("I", 10)`` (any case) as the console's variable; Refused in the console's words
    for a type or an index it does not take."""
    if not isinstance(kind, str):
        raise Refused(f"a variable's type is text such as 'I' or 'P', got {kind!r}")
    if isinstance(index, bool) or not isinstance(index, int):
        raise Refused(f"a variable's index is an int from 0 to 32767, got {index!r}")
    try:
        return VarRef(kind_of(kind), parse_index(str(index)))
    except InputError as exc:
        raise Refused(str(exc)) from None


def put_command(var: VarRef, value: object) -> Put:
    """The console's PUT of ``value`` to ``var``; Refused, before anything is sent, for a
    value it cannot write, saying how to write it."""
    words = _words(var, value)
    try:
        command = exchange_from_words("put", [var.kind.code, str(var.index), *words])
    except InputError as exc:
        raise Refused(f"put {var}: {exc} (nothing was sent)") from None
    assert isinstance(command, Put)
    return command


def _words(var: VarRef, value: object) -> list[str]:
    """The value as the words ``rac-console put`` takes for ``var``'s type."""
    kind = var.kind
    if kind.labels:
        items = (
            value if isinstance(value, Sequence) and not isinstance(value, str | bytes) else None
        )
        if items is not None and all(_number(item) for item in items):
            return [_number_text(item) for item in items]
    elif kind.code == "S":
        if isinstance(value, str):
            return [value]  # the string exactly, as one word of the shell
    elif kind.code == "IO":
        if isinstance(value, bool):
            return ["on" if value else "off"]
    elif kind.code == "I":
        if isinstance(value, int) and not isinstance(value, bool):
            return [str(value)]
    elif _number(value):
        return [_number_text(value)]
    raise Refused(f"put {var}: {kind.code} takes {takes(kind)}, got {value!r} (nothing was sent)")


def takes(kind: VarKind) -> str:
    """What Python value a type takes: ``an int``, ``a tuple of 3 floats (X Y Z)``."""
    if kind.labels:
        return f"a tuple of {kind.count} floats ({kind.value_hint})"
    return {
        "I": "an int",
        "F": "a float (or an int)",
        "D": "a float (or an int)",
        "S": "a str",
        "IO": "a bool (True for on, False for off)",
    }[kind.code]


def _number(value: object) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool)


def _number_text(value: Any) -> str:
    """A number as the console reads it: an int whole, a float by its shortest repr
    (which reads back as the same float; nan and inf are refused there, as typed)."""
    return str(value) if isinstance(value, int) else repr(float(value))


def python_value(kind: VarKind, variant: Variant) -> Value:
    """A GET's answer (checked by the session to fit ``kind``) as its Python type."""
    value = variant.value
    if kind.labels:
        return tuple(float(item) for item in value)
    if kind.code == "IO":
        return bool(value)
    if kind.code == "I":
        return int(value)
    if kind.code == "S":
        return str(value)
    return float(value)


def plain_value(variant: Variant) -> Value | None:
    """An answer to a line that names no variable (or not as that variable's type), as
    near a :data:`Value` as it comes: a number, a string, a bool, a tuple for an array
    of numbers; None for no value, or one no Value holds (:attr:`Sent.raw` has it)."""
    value = variant.value
    while isinstance(value, Variant):
        value = value.value
    if isinstance(value, list):
        if all(_number(item) or isinstance(item, Decimal) for item in value):
            return tuple(float(item) for item in value)
        return None
    if isinstance(value, Decimal):
        return float(value)
    if isinstance(value, bool | int | float | str):
        return value
    return None
