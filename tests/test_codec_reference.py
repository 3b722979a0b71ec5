"""The codec against DENSO's ``rac_string.c`` and an exact float32 reference.

Three findings of the side-by-side run with DENSO's own code are ours to fix: VT_EMPTY and
VT_NULL keep the comma of ``<VARTYPE>,<data>``; VT_R4 text is rounded once, straight to
float32 (as C's ``strtof``); empty array data is an empty array (spec section 3, decisions).
"""

from __future__ import annotations

import struct
from decimal import Decimal, localcontext
from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rac_console.protocol import (
    EncodeError,
    InputError,
    ProtocolError,
    Variant,
    encode_value,
    format_variant,
    kind_of,
    parse_response,
    parse_variant,
)
from rac_console.protocol.vartypes import ARRAY_ELEMENT_TYPES, VT, VT_ARRAY

# ------------------------------------------------------------- exact reference

_FLT_MAX = Fraction((2**24 - 1) * 2**104)


def nearest_float32(text: str) -> float | None:
    """The float32 nearest to the exact value of a decimal text, ties to even.

    None when it rounds beyond FLT_MAX (at or past the midpoint between FLT_MAX and
    2**128). Exact rational arithmetic: no double is involved on the way.
    """
    exact = Fraction(Decimal(text))
    negative = exact < 0 or (exact == 0 and text.strip().startswith("-"))
    size = abs(exact)
    if size == 0:
        return -0.0 if negative else 0.0
    exponent = size.numerator.bit_length() - size.denominator.bit_length()
    if Fraction(2) ** exponent > size:
        exponent -= 1  # now 2**exponent <= size < 2**(exponent + 1)
    quantum = Fraction(2) ** (max(exponent, -126) - 23)  # float32 spacing there
    count, rest = divmod(size, quantum)
    if rest > quantum / 2 or (rest == quantum / 2 and count % 2 == 1):
        count += 1
    value = count * quantum
    if value > _FLT_MAX:
        return None
    return -float(value) if negative else float(value)


def bits(x: float) -> int:
    return int.from_bytes(struct.pack("<f", x), "little")


def f32(pattern: int) -> float:
    value: float = struct.unpack("<f", pattern.to_bytes(4, "little"))[0]
    return value


def through_double(text: str) -> float | None:
    """Today's way, text to double to float32: what the vectors below must catch."""
    try:
        return f32(bits(float(text)))
    except OverflowError:
        return None


def midpoint(low_bits: int) -> Decimal:
    """The exact decimal value halfway between a float32 and the next one up."""
    low = Fraction(f32(low_bits))
    high = Fraction(f32(low_bits + 1)) if low_bits != 0x7F7FFFFF else Fraction(2**128)
    middle = (low + high) / 2
    with localcontext() as ctx:
        ctx.prec = 200  # a dyadic rational has a finite decimal expansion: this keeps it all
        return Decimal(middle.numerator) / Decimal(middle.denominator)


def nudged(value: Decimal, direction: int, hair: int = 30) -> str:
    """A decimal 10**-hair (relative) above or below value: inside one double's ulp."""
    with localcontext() as ctx:
        ctx.prec = 200
        return str(value + direction * abs(value) * Decimal(f"1e-{hair}"))


def r4(text: str) -> float | None:
    """Our codec's reading of VT_R4 text, None when it refuses it as out of range."""
    try:
        value: float | None = parse_variant("4," + text).value
        return value
    except ProtocolError as exc:
        assert "out of range" in str(exc)
        return None


def same_float32(ours: float | None, reference: float | None) -> bool:
    if ours is None or reference is None:
        return ours is reference
    return bits(ours) == bits(reference)


# ------------------------------------------------- 1. VT_EMPTY and VT_NULL


def test_empty_and_null_are_written_with_their_comma() -> None:
    assert format_variant(Variant(VT.EMPTY, None)) == "0,"
    assert format_variant(Variant(VT.NULL, None)) == "1,"
    assert format_variant(Variant(VT.VARIANT, Variant(VT.EMPTY, None))) == "12,(0,)"
    nested = Variant(VT.VARIANT | VT_ARRAY, [Variant(VT.EMPTY, None), Variant(VT.NULL, None)])
    assert format_variant(nested) == "8204,(0,),(1,)"


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("0,", Variant(VT.EMPTY, None)),
        ("0", Variant(VT.EMPTY, None)),
        ("1,", Variant(VT.NULL, None)),
        ("1", Variant(VT.NULL, None)),
        (" 1 , ", Variant(VT.NULL, None)),
        ("12,(0,)", Variant(VT.VARIANT, Variant(VT.EMPTY, None))),
        ("12,(0)", Variant(VT.VARIANT, Variant(VT.EMPTY, None))),
        (
            "8204,(0,),(1),( 1 , )",
            Variant(
                VT.VARIANT | VT_ARRAY,
                [Variant(VT.EMPTY, None), Variant(VT.NULL, None), Variant(VT.NULL, None)],
            ),
        ),
    ],
)
def test_empty_and_null_are_read_with_or_without_the_comma(text: str, expected: Variant) -> None:
    assert parse_variant(text) == expected


def test_empty_reply_to_a_get_is_read_either_way() -> None:
    assert parse_response("0,0,").variant == Variant(VT.EMPTY, None)
    assert parse_response("0,1").variant == Variant(VT.NULL, None)


# ------------------------------------------------------- 2. VT_R4 rounding

_ONE = 0x3F800000  # 1.0: even mantissa, so its upper midpoint ties down to it
_ONE_UP = 0x3F800001  # odd mantissa: its upper midpoint ties up to the next one
_BIG = 0x7F000000  # 2**127
_FLT_MAX_BITS = 0x7F7FFFFF

# (text, float32 bits, or None for out of range); every one is rounded wrongly through a double
MIDPOINT_VECTORS = [
    (nudged(midpoint(_ONE), +1), _ONE + 1),
    (nudged(midpoint(_ONE_UP), -1), _ONE_UP),
    ("-" + nudged(midpoint(_ONE), +1), 0x80000000 | (_ONE + 1)),
    (nudged(midpoint(_BIG), +1), _BIG + 1),
    (nudged(midpoint(0x00000000), +1), 0x00000001),  # half the smallest subnormal, and a bit
    (nudged(midpoint(0x00000003), -1), 0x00000003),  # between subnormals 3 and 4 (even)
    (nudged(midpoint(0x0000_7FFF), -1), 0x0000_7FFF),
    (nudged(midpoint(_FLT_MAX_BITS), -1), _FLT_MAX_BITS),  # just under the overflow point
    ("-" + nudged(midpoint(_FLT_MAX_BITS), -1), 0x80000000 | _FLT_MAX_BITS),
    ("16777217.000000000000000000001", 0x4B800001),  # 2**24 + 1 and a bit: up, not even
    ("33554437.99999999999999999999", 0x4C000001),  # 2**25 + 6 less a bit: down to 2**25 + 4
]

# exactly at a midpoint (ties to even) and plainly out of range: double rounding agrees here
TIE_AND_RANGE_VECTORS = [
    (str(midpoint(_ONE)), _ONE),
    (str(midpoint(_ONE_UP)), _ONE_UP + 1),
    (str(midpoint(0x00000000)), 0x00000000),
    ("16777217", 0x4B800000),
    ("3.4028235e38", _FLT_MAX_BITS),
    ("3.40282356e38", _FLT_MAX_BITS),
    ("-3.4028235e38", 0x80000000 | _FLT_MAX_BITS),
    (str(midpoint(_FLT_MAX_BITS)), None),  # the overflow point itself ties away, to 2**128
    (nudged(midpoint(_FLT_MAX_BITS), +1), None),
    ("3.4028236e38", None),
    ("1e39", None),
    ("-1e400", None),
    ("1e-46", 0x00000000),
    ("-1e-400", 0x80000000),
    ("123.01", 0x42F6051F),
]


@pytest.mark.parametrize(("text", "expected"), MIDPOINT_VECTORS, ids=lambda v: str(v)[:24])
def test_r4_text_near_a_float32_midpoint_rounds_once(text: str, expected: int | None) -> None:
    reference = nearest_float32(text)
    assert reference is not None and bits(reference) == expected  # the vector is right
    assert not same_float32(through_double(text), reference)  # and catches double rounding
    assert same_float32(r4(text), reference)


@pytest.mark.parametrize(("text", "expected"), TIE_AND_RANGE_VECTORS, ids=lambda v: str(v)[:24])
def test_r4_ties_go_to_even_and_overflow_starts_at_the_midpoint(
    text: str, expected: int | None
) -> None:
    reference = nearest_float32(text)
    assert (None if reference is None else bits(reference)) == expected
    assert same_float32(r4(text), reference)


def test_r4_just_under_the_overflow_point_is_flt_max_not_an_error() -> None:
    text = nudged(midpoint(_FLT_MAX_BITS), -1)
    assert through_double(text) is None  # the old way refused it
    value = parse_variant("4," + text).value
    assert bits(value) == _FLT_MAX_BITS
    assert format_variant(Variant(VT.R4, value)) == "4,3.4028235e+38"


def test_typed_r4_values_are_rounded_once() -> None:
    text = nudged(midpoint(_ONE), +1)
    variant, wire = encode_value(kind_of("F"), text)
    assert bits(variant.value) == _ONE + 1
    assert wire == "4,1.0000001"
    position = kind_of("P").value_from_text(f"1 2 3 4 5 {text} -1")
    assert bits(position.value[5]) == _ONE + 1
    top = nudged(midpoint(_FLT_MAX_BITS), -1)
    assert bits(kind_of("F").value_from_text(top).value) == _FLT_MAX_BITS
    with pytest.raises(InputError, match="out of range"):
        kind_of("F").value_from_text(str(midpoint(_FLT_MAX_BITS)))


def test_shortest_r4_text_is_checked_with_the_rounding_a_reader_uses() -> None:
    # "7.038531e-26" is a double on the midpoint below 0x15AE43FE, and a hair under it:
    # rounded through a double it looks like the shortest text of 0x15AE43FE, but strtof
    # reads it as 0x15AE43FD. The shortest text that reads back is one digit longer.
    value = f32(0x15AE43FE)
    assert format_variant(Variant(VT.R4, value)) == "4,7.0385313e-26"
    assert bits(parse_variant("4,7.038531e-26").value) == 0x15AE43FD
    assert format_variant(Variant(VT.R4, f32(0x15AE43FD))) == "4,7.0385307e-26"


@pytest.mark.parametrize(
    "pattern",
    [_ONE, _ONE + 1, _ONE_UP + 1, 0x00000001, 0x00800000, _FLT_MAX_BITS, 0x4B800001, 0x15AE43FE],
)
def test_written_r4_text_reads_back_exactly(pattern: int) -> None:
    for value in (f32(pattern), -f32(pattern)):
        text = format_variant(Variant(VT.R4, value)).partition(",")[2]
        assert same_float32(nearest_float32(text), value)
        assert same_float32(parse_variant("4," + text).value, value)


@given(st.floats(width=32, allow_nan=False, allow_infinity=False))
@settings(max_examples=300, deadline=None)
def test_any_float32_written_then_read_keeps_its_bits(value: float) -> None:
    text = format_variant(Variant(VT.R4, value)).partition(",")[2]
    assert bits(parse_variant("4," + text).value) == bits(value)
    assert same_float32(nearest_float32(text), value)  # and under strtof's exact rounding
    digits = text.lower().partition("e")[0].lstrip("-").replace(".", "").strip("0")
    assert len(digits) <= 9


@st.composite
def _near_midpoints(draw: st.DrawFn) -> str:
    """Decimal text at, or a hair away from, a random float32 midpoint."""
    middle = midpoint(draw(st.integers(0, _FLT_MAX_BITS)))
    direction = draw(st.sampled_from([-1, 0, 1]))
    text = nudged(middle, direction, draw(st.integers(17, 60))) if direction else str(middle)
    return draw(st.sampled_from(["", "-"])) + text


def _plain_decimals() -> st.SearchStrategy[str]:
    return st.builds(
        lambda sign, digits, point, exponent: (
            f"{sign}{digits[:point]}.{digits[point:]}e{exponent}"
            if point < len(digits)
            else f"{sign}{digits}e{exponent}"
        ),
        st.sampled_from(["", "-", "+"]),
        st.text("0123456789", min_size=1, max_size=40),
        st.integers(1, 40),
        st.integers(-80, 45),
    )


@given(st.one_of(_near_midpoints(), _plain_decimals()))
@settings(max_examples=400, deadline=None)
def test_r4_parse_is_the_exact_nearest_float32(text: str) -> None:
    assert same_float32(r4(text), nearest_float32(text))


# ------------------------------------------------------- 3. empty arrays

ARRAY_TYPES = sorted(vt | VT_ARRAY for vt in ARRAY_ELEMENT_TYPES)


@pytest.mark.parametrize("vt", ARRAY_TYPES)
def test_empty_array_data_is_an_empty_array_for_every_element_type(vt: int) -> None:
    assert parse_variant(f"{vt},") == Variant(vt, [])
    assert parse_variant(f"{vt}, \t") == Variant(vt, [])
    assert format_variant(Variant(vt, [])) == f"{vt},"


def test_empty_arrays_inside_a_variant_array() -> None:
    text = "8204,(8200,),(8196,)"
    variant = Variant(8204, [Variant(8200, []), Variant(8196, [])])
    assert parse_variant(text) == variant
    assert format_variant(variant) == text


@pytest.mark.parametrize(
    "variant",
    [
        Variant(8200, [""]),
        Variant(8200, ["  "]),
        Variant(8199, [""]),
        Variant(8204, [Variant(8200, [""])]),
    ],
    ids=repr,
)
def test_one_empty_string_in_an_array_is_refused_with_the_reason(variant: Variant) -> None:
    with pytest.raises(EncodeError, match="reads back as an empty array"):
        format_variant(variant)


def test_empty_strings_beside_others_are_written() -> None:
    assert format_variant(Variant(8200, ["", ""])) == "8200,,"
    assert parse_variant("8200,,") == Variant(8200, ["", ""])
    assert format_variant(Variant(8200, ["", "a"])) == "8200,,a"
    assert format_variant(Variant(8204, [Variant(8, "")])) == "8204,(8,)"


def test_an_empty_element_of_a_numeric_array_is_an_error() -> None:
    for text in ("8196,,", "8196,1,", "8194,,1"):
        with pytest.raises(ProtocolError):
            parse_variant(text)
    assert parse_variant("8196,1") == Variant(8196, [1.0])  # one element is not empty
