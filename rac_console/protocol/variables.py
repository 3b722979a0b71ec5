"""The controller's variable types (I, F, D, S, V, P, J, T, IO) and their values.

Each :class:`VarKind` knows its VARTYPE, its field labels, how to turn what a
person types into a :class:`Variant`, and which replies can belong to a GET of it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from .errors import EncodeError, InputError
from .text import close_match, scalar_text
from .variant import Variant, format_variant, r4_from_text
from .vartypes import INTEGER_RANGES, NUMERIC_TYPES, VT, VT_ARRAY, element_type, is_array

R4_ARRAY = VT.R4 | VT_ARRAY
MAX_INDEX = 32767

_NUMBER_RE = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_INTEGER_RE = re.compile(r"[+-]?(?:\d+|0[xX][0-9a-fA-F]+)", re.ASCII)
_TRUE_WORDS = ("on", "1", "true", "-1")
_FALSE_WORDS = ("off", "0", "false")
_INTEGER_VTS = frozenset(INTEGER_RANGES) | {VT.BOOL}


@dataclass(frozen=True, eq=False)
class VarKind:
    """One variable type of the controller. There is one of each (:data:`KINDS`), so
    it is equal only to itself: hashing one (a request cache's key, on every poll) is
    the object's identity, not its four fields."""

    code: str
    title: str
    vt: int
    labels: tuple[str, ...] = ()

    @property
    def count(self) -> int:
        """Element count of an array type, 0 for a scalar."""
        return len(self.labels)

    @property
    def value_hint(self) -> str:
        """What ``put`` still needs, as a hint: ``X Y Z Rx Ry Rz Fig``."""
        if self.labels:
            return " ".join(self.labels)
        return {"I": "INTEGER", "F": "NUMBER", "D": "NUMBER", "S": "TEXT", "IO": "on|off"}[
            self.code
        ]

    def value_from_text(self, text: str) -> Variant:
        """Parse the value part of a ``put`` as typed; raise InputError with a fix."""
        text = text.strip()
        if self.code == "S":
            value = _string(text)
            if "\r" in value or "\n" in value:
                raise InputError("S cannot hold CR or LF: CR ends a RAC frame")
            return Variant(VT.BSTR, value)
        if self.labels:
            return Variant(R4_ARRAY, self._floats(text))
        if not text:
            raise InputError(f"{self.code} needs a value: {self.value_hint}")
        if self.code == "IO":
            word = text.lower()
            if word in _TRUE_WORDS or word in _FALSE_WORDS:
                return Variant(VT.BOOL, word in _TRUE_WORDS)
            raise InputError(f"IO needs on or off (also 1/0, true/false), got {text!r}")
        if self.code == "I":
            return Variant(VT.I4, _integer(text))
        return Variant(self.vt, _number(text, self.vt, self.code))

    def _floats(self, text: str) -> list[float]:
        parts = [p for p in re.split(r"[\s,]+", text) if p]
        if len(parts) != self.count:
            raise InputError(
                f"{self.code} needs {self.count} values: {self.value_hint}, got {len(parts)}"
            )
        return [
            _number(p, VT.R4, f"{self.code} {label}")
            for p, label in zip(parts, self.labels, strict=True)
        ]

    def reply_problem(self, variant: Variant) -> str | None:
        """Why a successful GET reply cannot be for this type, or None if it can."""
        vt = variant.vt
        if self.labels:
            if not is_array(vt) or element_type(vt) not in NUMERIC_TYPES:
                return f"{self.code} should answer an array of numbers, got VARTYPE {vt}"
            if len(variant.value) != self.count:
                return f"{self.code} should answer {self.count} values, got {len(variant.value)}"
            return None
        if self.code == "S":
            return None if vt == VT.BSTR else f"S should answer a string, got VARTYPE {vt}"
        if self.code in ("I", "IO"):
            return (
                None
                if vt in _INTEGER_VTS
                else f"{self.code} should answer an integer, got VARTYPE {vt}"
            )
        return (
            None if vt in NUMERIC_TYPES else f"{self.code} should answer a number, got VARTYPE {vt}"
        )

    def fields(self, variant: Variant) -> list[tuple[str, str]]:
        """Labelled display fields: ``[("X", "1.5"), ...]``, or one ``("", text)``."""
        if self.code == "IO" and not isinstance(variant.value, list):
            return [("", "ON" if variant.value else "OFF")]
        if self.labels and isinstance(variant.value, list) and len(variant.value) == self.count:
            return [
                (label, scalar_text(v)) for label, v in zip(self.labels, variant.value, strict=True)
            ]
        if isinstance(variant.value, list):
            return [(str(i), scalar_text(v)) for i, v in enumerate(variant.value)]
        return [("", scalar_text(variant.value))]


KINDS: dict[str, VarKind] = {
    k.code: k
    for k in (
        VarKind("I", "integer", VT.I4),
        VarKind("F", "single float", VT.R4),
        VarKind("D", "double", VT.R8),
        VarKind("S", "string", VT.BSTR),
        VarKind("V", "vector", R4_ARRAY, ("X", "Y", "Z")),
        VarKind("P", "position", R4_ARRAY, ("X", "Y", "Z", "Rx", "Ry", "Rz", "Fig")),
        VarKind("J", "joints", R4_ARRAY, tuple(f"J{i}" for i in range(1, 9))),
        VarKind(
            "T", "transform", R4_ARRAY, ("X", "Y", "Z", "Ox", "Oy", "Oz", "Ax", "Ay", "Az", "Fig")
        ),
        VarKind("IO", "I/O bit", VT.BOOL),
    )
}

TYPE_CHOICES = " ".join(KINDS)


def kind_of(code: str) -> VarKind:
    kind = KINDS.get(code.upper())
    if kind is None:
        meant = close_match(code, KINDS)
        guess = f"did you mean {meant}? " if meant is not None else ""
        raise InputError(f"unknown variable type {code!r}: {guess}use one of {TYPE_CHOICES}")
    return kind


def parse_index(text: str) -> int:
    if not text.isascii() or not text.isdigit() or len(text) > 6:
        raise InputError(f"index must be a whole number from 0 to {MAX_INDEX}, got {text!r}")
    index = int(text)
    if index > MAX_INDEX:
        raise InputError(f"index {index} is too large: use 0 to {MAX_INDEX}")
    return index


def encode_value(kind: VarKind, text: str) -> tuple[Variant, str]:
    """The Variant for a typed value and its wire text; InputError when refused."""
    variant = kind.value_from_text(text)
    try:
        return variant, format_variant(variant)
    except EncodeError as exc:
        raise InputError(f"{kind.code}: {exc}") from None


def _string(text: str) -> str:
    """A typed string: as typed, or inside one pair of quotes to keep outer spaces.

    Nothing is guessed: no value, or quotes that do not enclose exactly one string
    (``"a" "b"``), is refused rather than written as something nobody typed.
    """
    if not text:
        raise InputError('S needs a value: write "" for an empty string, e.g. put S 10 ""')
    quote = text[0]
    if quote not in "\"'":
        return text
    if len(text) < 2 or text[-1] != quote or quote in text[1:-1]:
        other = "'" if quote == '"' else '"'
        raise InputError(
            f"a string in quotes is one value, quotes at both ends: put S 10 {quote}a b{quote}"
            f" (for a {quote} inside, quote with {other})"
        )
    return text[1:-1]


def _integer(text: str) -> int:
    if len(text) > 40 or not _INTEGER_RE.fullmatch(text):
        raise InputError(f"I needs a whole number such as 123 or -5, got {text!r}")
    value = int(text, 0) if "x" in text.lower() else int(text)
    low, high = INTEGER_RANGES[VT.I4]
    if not low <= value <= high:
        raise InputError(f"{value} is out of range for I (VT_I4, {low} to {high})")
    return value


def _number(text: str, vt: int, what: str) -> float:
    if not _NUMBER_RE.fullmatch(text):
        raise InputError(f"{what} needs a number such as 1.5 or -2e3, got {text!r}")
    if vt == VT.R4:
        try:
            return r4_from_text(text)  # rounded once, as the controller's strtof would
        except OverflowError:
            raise InputError(f"{text} is out of range for {what} (VT_R4, up to ±3.4e38)") from None
    value = float(text)
    if not math.isfinite(value):
        raise InputError(f"{text} is out of range for {what} (VT_R8)")
    return value
