"""VARIANT text codec: ``<VARTYPE>,<data>`` both ways (spec section 3).

A decoded value is a :class:`Variant` holding the VARTYPE and a Python value:
``None`` (VT_EMPTY, VT_NULL), ``int`` (integer types, VT_ERROR as unsigned
32-bit), ``float`` (VT_R4, VT_R8), ``Decimal`` (VT_CY), ``str`` (VT_BSTR,
VT_DATE), ``bool`` (VT_BOOL), a nested ``Variant`` (VT_VARIANT) or a ``list`` of
element values (any VT_ARRAY type).

VT_R4 values are kept canonical: the double nearest to the shortest decimal that
rounds to the same float32, so ``4,123.01`` decodes to ``123.01`` and writes
back as ``123.01``. VT_R4 text is rounded once, straight to the nearest float32
(ties to even, as C's ``strtof``), never to a double first.

VT_EMPTY and VT_NULL are written ``0,`` and ``1,`` (the form DENSO's ``rac_string.c``
writes and reads) and read with or without the comma; empty array data is an empty array.
"""

from __future__ import annotations

import math
import re
import struct
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from functools import lru_cache
from typing import Any

from .errors import EncodeError, ProtocolError
from .vartypes import INTEGER_RANGES, VT, element_type, is_array, is_known, vt_name

_BLANKS = " \t"
_INT_RE = re.compile(r"[+-]?\d+", re.ASCII)
_HEX_RE = re.compile(r"0[xX][0-9a-fA-F]+", re.ASCII)
_FLOAT_RE = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_CY_RE = re.compile(r"[+-]?(?:\d+(?:\.\d{0,4})?|\.\d{1,4})", re.ASCII)
_CY_LIMIT = Decimal(2**63) / 10000
_MAX_DIGITS = 40  # longer integers are refused before int() is asked to convert them
MAX_NESTING = 16  # VT_VARIANT inside VT_VARIANT, at most this deep


@dataclass(frozen=True, slots=True)
class Variant:
    """A VARTYPE and its value; equal when both are equal."""

    vt: int
    value: Any

    def to_json(self) -> Any:
        """The JSON form of the value: nested VARIANTs as ``{"vt": N, "value": V}``."""
        return json_value(self.value)


def json_value(value: Any) -> Any:
    if isinstance(value, Variant):
        return {"vt": value.vt, "value": json_value(value.value)}
    if isinstance(value, list):
        return [json_value(v) for v in value]
    if isinstance(value, Decimal):
        return float(value)
    return value


# --------------------------------------------------------------------- floats

_F32 = struct.Struct("<f")
_FLOAT32_TOP = 2.0**128  # the first power of two float32 cannot hold


def _to_float32(x: float) -> float:
    """x rounded once to float32, ties to even.

    OverflowError from the midpoint between FLT_MAX and 2**128 on, where C's ``(float)x``
    gives infinity.
    """
    value: float = _F32.unpack(_F32.pack(x))[0]
    return value


def _midpoint_gap(x: float) -> float:
    """Half the float32 spacing when x lies exactly halfway between two float32 neighbours.

    0.0 otherwise. Only on such a point can rounding decimal text to a double first pick
    the wrong float32: the text may lie a hair above or below it, the double cannot.
    """
    if not 0 < abs(x) < _FLOAT32_TOP:
        return 0.0
    # float32 spacing is 2**(e-24) in [2**(e-1), 2**e), and 2**-149 below 2**-126
    shift = min(25 - math.frexp(x)[1], 150)
    scaled = math.ldexp(x, shift)
    return math.ldexp(1.0, -shift) if scaled.is_integer() and scaled % 2 == 1 else 0.0


def _nearest_float32(text: str, x: float) -> float:
    """The float32 nearest to the exact value of decimal ``text`` (``x = float(text)``).

    Rounds once, as C's ``strtof``: exact decimal arithmetic settles a double that fell on
    a midpoint. OverflowError when the value rounds beyond FLT_MAX.
    """
    gap = _midpoint_gap(x)
    if gap:
        exact, middle = Decimal(text), Decimal(x)  # both exact
        if exact != middle:
            # the neighbour on the text's side; copysign keeps -0.0 for a negative text
            x = math.copysign(x + gap if exact > middle else x - gap, x)
    return _to_float32(x)


def canonical_r4(x: float) -> float:
    """The double nearest to the shortest decimal that rounds to float32(x).

    x is a value, not text: it is rounded to float32 once. Raises OverflowError when x is
    outside float32's range.
    """
    if x == 0:
        return x  # keeps the sign of -0.0, which the cache below would confuse with 0.0
    value = _r4_of_double(x)[0]
    if value != value:  # NaN marks out of range
        raise OverflowError(f"{x!r} is beyond float32's range")
    return value


def r4_from_text(text: str) -> float:
    """The canonical VT_R4 value of decimal text, rounded once to the nearest float32.

    Raises OverflowError when the text rounds beyond FLT_MAX (or is not finite).
    """
    x = float(text)
    if x == 0:
        return x  # also text too small for a double: it rounds to a zero of its sign
    value, gap = _r4_of_double(x)
    if gap:  # rare: a double on a float32 midpoint, so the text decides the side
        return canonical_r4(_nearest_float32(text, x))
    if value != value:
        raise OverflowError(f"{text} is beyond float32's range")
    return value


@lru_cache(maxsize=8192)
def _r4_of_double(x: float) -> tuple[float, float]:
    """``canonical_r4(x)`` (NaN when out of range) and x's midpoint gap, cached together.

    The parser is on every poll's path and polled values repeat, so one cache lookup per
    element keeps the exact rounding off the common path.
    """
    if not math.isfinite(x):
        return math.nan, 0.0
    gap = _midpoint_gap(x)
    try:
        f32 = _to_float32(x)
    except OverflowError:
        return math.nan, gap
    return _shortest_r4(f32), gap


def _shortest_r4(f32: float) -> float:
    """The double of the shortest decimal text that reads back (``strtof``) as f32."""
    for digits in range(1, 10):
        mantissa, _, exponent = f"{f32:.{digits - 1}e}".partition("e")
        sign = "-" if mantissa.startswith("-") else ""
        integer = int(mantissa.lstrip("-").replace(".", ""))
        scale = int(exponent) - (digits - 1)
        # The nearest n-digit decimal, and its neighbours: at a power of two the
        # neighbour can round-trip where the nearest does not.
        for candidate_digits in (integer, integer - 1, integer + 1):
            candidate = float(f"{sign}{candidate_digits}e{scale}")
            try:
                # what float_text writes must read back as f32, and the double itself
                # (rounded as a value by canonical_r4) must too
                if (
                    _to_float32(candidate) == f32
                    and _nearest_float32(repr(candidate), candidate) == f32
                ):
                    return candidate
            except OverflowError:
                continue
    return f32  # pragma: no cover - 9 significant digits always round-trip


def float_text(x: float) -> str:
    """Shortest round-trip text, with an integer value written without ``.0``."""
    text = repr(x)
    return text[:-2] if text.endswith(".0") else text


# ------------------------------------------------------------------- parsing


def parse_variant(text: str, _depth: int = 0) -> Variant:
    """Decode ``<VARTYPE>,<data>``; raise :class:`ProtocolError` on anything else."""
    if _depth > MAX_NESTING:
        raise ProtocolError(f"VT_VARIANT nested more than {MAX_NESTING} deep")
    vt_text, _, data = text.partition(",")
    vt_field = vt_text.strip(_BLANKS)
    if len(vt_field) > 6 or not _INT_RE.fullmatch(vt_field):
        raise ProtocolError(f"VARTYPE must be a number, got {vt_field!r}")
    vt = int(vt_field)
    if not is_known(vt):
        raise ProtocolError(f"unsupported VARTYPE {vt}")
    if is_array(vt):
        return Variant(
            vt, [_parse_scalar(element_type(vt), e, _depth) for e in split_elements(data)]
        )
    return Variant(vt, _parse_scalar(vt, data, _depth))


def split_elements(data: str) -> list[str]:
    """Split array data at commas outside parentheses; empty data is an empty array."""
    if not data.strip(_BLANKS):
        return []
    parts: list[str] = []
    depth = 0
    start = 0
    for i, ch in enumerate(data):
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
            if depth < 0:
                raise ProtocolError(f"unbalanced ')' in {data!r}")
        elif ch == "," and depth == 0:
            parts.append(data[start:i])
            start = i + 1
    if depth:
        raise ProtocolError(f"unbalanced '(' in {data!r}")
    parts.append(data[start:])
    return parts


def _parse_int(field: str, vt: int) -> int:
    if len(field) > _MAX_DIGITS or not _INT_RE.fullmatch(field):
        raise ProtocolError(f"{vt_name(vt)} needs an integer, got {field!r}")
    value = int(field)
    low, high = INTEGER_RANGES[VT(vt)]
    if not low <= value <= high:
        raise ProtocolError(f"{value} is out of range for {vt_name(vt)} ({low}..{high})")
    return value


def _parse_float(field: str, vt: int) -> float:
    if not _FLOAT_RE.fullmatch(field):
        raise ProtocolError(f"{vt_name(vt)} needs a number, got {field!r}")
    if vt == VT.R4:
        try:
            return r4_from_text(field)
        except OverflowError:
            raise ProtocolError(f"{field!r} is out of range for VT_R4") from None
    value = float(field)
    if not math.isfinite(value):
        raise ProtocolError(f"{field!r} is out of range for {vt_name(vt)}")
    return value


def parse_hresult_number(field: str) -> int:
    """Signed decimal, unsigned decimal or hex (any case) to an unsigned 32-bit code."""
    if len(field) > _MAX_DIGITS:
        raise ProtocolError(f"a result code must fit 32 bits, got {field[:20]!r}...")
    if _HEX_RE.fullmatch(field):
        value = int(field, 16)
    elif _INT_RE.fullmatch(field):
        value = int(field)
    else:
        raise ProtocolError(f"a result code must be a number, got {field!r}")
    if not -(2**31) <= value < 2**32:
        raise ProtocolError(f"result code {field!r} does not fit 32 bits")
    return value & 0xFFFFFFFF


def _parse_scalar(vt: int, data: str, depth: int = 0) -> Any:
    field = data.strip(_BLANKS)
    if vt in (VT.EMPTY, VT.NULL):
        if field:
            raise ProtocolError(f"{vt_name(vt)} carries no data, got {data!r}")
        return None
    if vt in INTEGER_RANGES:
        return _parse_int(field, vt)
    if vt in (VT.R4, VT.R8):
        return _parse_float(field, vt)
    if vt == VT.BOOL:
        lowered = field.lower()
        if lowered in ("true", "false"):
            return lowered == "true"
        if len(field) > _MAX_DIGITS or not _INT_RE.fullmatch(field):
            raise ProtocolError(f"VT_BOOL needs 0, -1, True or False, got {field!r}")
        return int(field) != 0
    if vt == VT.CY:
        if not _CY_RE.fullmatch(field):
            raise ProtocolError(
                f"VT_CY needs a decimal with up to 4 fraction digits, got {field!r}"
            )
        value = Decimal(field)
        if abs(value) >= _CY_LIMIT:
            raise ProtocolError(f"{field!r} is out of range for VT_CY")
        return value
    if vt == VT.ERROR:
        try:
            return parse_hresult_number(field)
        except ProtocolError:
            raise ProtocolError(f"VT_ERROR needs an error code, got {field!r}") from None
    if vt in (VT.BSTR, VT.DATE):
        return data
    if vt == VT.VARIANT:
        if len(field) < 2 or field[0] != "(" or field[-1] != ")":
            raise ProtocolError(f"VT_VARIANT data must be '(vt,data)', got {data!r}")
        inner = field[1:-1]
        split_elements(inner)  # rejects unbalanced parentheses inside
        return parse_variant(inner, depth + 1)
    raise ProtocolError(f"unsupported VARTYPE {vt}")  # pragma: no cover - is_known guards


# ----------------------------------------------------------------- formatting

_TOP, _ELEMENT, _NESTED = "top", "element", "nested"


def format_variant(variant: Variant) -> str:
    """Encode a Variant; raise :class:`EncodeError` when it cannot be written."""
    return _format(variant, _TOP)


def _format(variant: Variant, where: str) -> str:
    vt = variant.vt
    if not is_known(vt):
        raise EncodeError(f"unsupported VARTYPE {vt}")
    if vt in (VT.EMPTY, VT.NULL):
        if variant.value is not None:
            raise EncodeError(f"{vt_name(vt)} carries no value")
        return f"{vt},"  # no data, but the comma of <VARTYPE>,<data>, as rac_string.c writes
    if is_array(vt):
        values = variant.value
        if not isinstance(values, (list, tuple)):
            raise EncodeError(f"{vt_name(vt)} needs a list of values")
        base = element_type(vt)
        if (
            base in (VT.BSTR, VT.DATE)
            and len(values) == 1
            and isinstance(values[0], str)
            and not values[0].strip(_BLANKS)
        ):
            raise EncodeError(
                f"{vt_name(vt)} holding one empty or blank string cannot be written:"
                f" '{vt},' reads back as an empty array"
            )
        return f"{vt}," + ",".join(_format_scalar(base, v, _ELEMENT) for v in values)
    return f"{vt}," + _format_scalar(vt, variant.value, where)


def _format_scalar(vt: int, value: Any, where: str) -> str:
    name = vt_name(vt)
    if vt in INTEGER_RANGES:
        if isinstance(value, bool) or not isinstance(value, int):
            raise EncodeError(f"{name} needs an integer, got {value!r}")
        low, high = INTEGER_RANGES[VT(vt)]
        if not low <= value <= high:
            raise EncodeError(f"{value} is out of range for {name} ({low}..{high})")
        return str(value)
    if vt in (VT.R4, VT.R8):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise EncodeError(f"{name} needs a number, got {value!r}")
        x = float(value)
        if not math.isfinite(x):
            raise EncodeError(f"{value!r} is out of range for {name}")
        if vt == VT.R4:
            try:
                x = canonical_r4(x)
            except OverflowError:
                raise EncodeError(f"{value!r} is out of range for VT_R4") from None
        return float_text(x)
    if vt == VT.BOOL:
        if not isinstance(value, bool):
            raise EncodeError(f"VT_BOOL needs true or false, got {value!r}")
        return "-1" if value else "0"
    if vt == VT.CY:
        return _format_currency(value)
    if vt == VT.ERROR:
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**32:
            raise EncodeError(f"VT_ERROR needs a 32-bit code, got {value!r}")
        return str(value - 2**32 if value >= 2**31 else value)
    if vt in (VT.BSTR, VT.DATE):
        return _check_text(value, name, where)
    if vt == VT.VARIANT:
        if not isinstance(value, Variant):
            raise EncodeError(f"VT_VARIANT needs a nested Variant, got {value!r}")
        return "(" + _format(value, _NESTED) + ")"
    raise EncodeError(f"unsupported VARTYPE {vt}")  # pragma: no cover


def _format_currency(value: Any) -> str:
    if isinstance(value, bool) or not isinstance(value, (int, Decimal)):
        raise EncodeError(f"VT_CY needs a decimal number, got {value!r}")
    try:
        amount = Decimal(value)
        if not amount.is_finite() or abs(amount) >= _CY_LIMIT:
            raise EncodeError(f"{value} is out of range for VT_CY")
        if amount != amount.quantize(Decimal("0.0001")):
            raise EncodeError(f"VT_CY takes at most 4 fraction digits, got {value}")
    except InvalidOperation:
        raise EncodeError(f"{value} is out of range for VT_CY") from None
    text = format(amount.normalize(), "f")
    return "0" if text in ("-0", "0") else text


def _check_text(value: Any, name: str, where: str) -> str:
    if not isinstance(value, str):
        raise EncodeError(f"{name} needs text, got {value!r}")
    if "\r" in value or "\n" in value:
        raise EncodeError("a string cannot contain CR or LF (CR ends a RAC frame)")
    control = next((ch for ch in value if ord(ch) < 0x20 or ord(ch) == 0x7F), None)
    if control is not None:
        raise EncodeError(
            f"a string cannot hold the control character {control!r}: RAC strings are plain text"
        )
    if where == _TOP:
        return value
    if where == _ELEMENT and "," in value:
        raise EncodeError(f"an array element cannot contain a comma: {value!r}")
    depth = 0
    for ch in value:
        depth += (ch == "(") - (ch == ")")
        if depth < 0:
            break
    if depth:
        raise EncodeError(
            f"text inside an array or VT_VARIANT needs balanced parentheses: {value!r}"
        )
    return value
