"""Property tests: any valid value survives format-then-parse; no text crashes the parsers."""

from __future__ import annotations

import contextlib
import string
import struct
from decimal import Decimal

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rac_console.engine.commands.builtin import parse_command
from rac_console.protocol import (
    RacError,
    Variant,
    format_variant,
    parse_response,
    parse_variant,
)
from rac_console.protocol.variant import canonical_r4
from rac_console.protocol.vartypes import ARRAY_ELEMENT_TYPES, INTEGER_RANGES, VT, VT_ARRAY
from rac_console.sim.controller import SimulatedController

TEXT_CHARS = st.characters(min_codepoint=0x20, max_codepoint=0x7E)


def _balanced(text: str) -> bool:
    depth = 0
    for ch in text:
        depth += (ch == "(") - (ch == ")")
        if depth < 0:
            return False
    return depth == 0


def _r4_values() -> st.SearchStrategy[float]:
    return st.floats(width=32, allow_nan=False, allow_infinity=False).map(canonical_r4)


def scalar_values(vt: int, where: str) -> st.SearchStrategy:
    """Values a scalar of this VARTYPE can hold where it stands (top, element or nested)."""
    if vt in INTEGER_RANGES:
        low, high = INTEGER_RANGES[VT(vt)]
        return st.integers(low, high)
    if vt == VT.R4:
        return _r4_values()
    if vt == VT.R8:
        return st.floats(allow_nan=False, allow_infinity=False)
    if vt == VT.BOOL:
        return st.booleans()
    if vt == VT.ERROR:
        return st.integers(0, 2**32 - 1)
    if vt == VT.CY:
        return st.decimals(
            min_value=Decimal("-9e14"),
            max_value=Decimal("9e14"),
            places=4,
            allow_nan=False,
            allow_infinity=False,
        )
    text = st.text(TEXT_CHARS, max_size=20)
    if where == "element":
        return text.filter(lambda s: "," not in s and _balanced(s))
    if where == "nested":
        return text.filter(_balanced)
    return text


SCALAR_TYPES = sorted(ARRAY_ELEMENT_TYPES - {VT.VARIANT})


def variants(depth: int = 2, where: str = "top") -> st.SearchStrategy[Variant]:
    scalar = st.sampled_from(SCALAR_TYPES).flatmap(
        lambda vt: scalar_values(vt, where).map(lambda v: Variant(vt, v))
    )
    array = st.sampled_from(SCALAR_TYPES).flatmap(
        lambda vt: (
            st.lists(scalar_values(vt, "element"), max_size=6)
            .filter(lambda vs: not (len(vs) == 1 and isinstance(vs[0], str) and not vs[0].strip()))
            .map(lambda vs: Variant(vt | VT_ARRAY, vs))
        )
    )
    empty = st.sampled_from([Variant(VT.EMPTY, None), Variant(VT.NULL, None)])
    options = [scalar, array, empty]
    if depth > 0:
        nested = variants(depth - 1, "nested")
        options.append(nested.map(lambda v: Variant(VT.VARIANT, v)))
        options.append(
            st.lists(nested, max_size=4).map(lambda vs: Variant(VT.VARIANT | VT_ARRAY, vs))
        )
    return st.one_of(options)


@pytest.mark.slow
@given(variants())
@settings(max_examples=400)
def test_parse_of_format_gives_the_value_back(variant: Variant) -> None:
    assert parse_variant(format_variant(variant)) == variant


@given(_r4_values())
def test_r4_text_rounds_to_the_same_float32(value: float) -> None:
    text = format_variant(Variant(VT.R4, value)).partition(",")[2]
    assert struct.pack("<f", float(text)) == struct.pack("<f", value)
    mantissa = text.lower().partition("e")[0].replace("-", "").replace(".", "")
    assert len(mantissa.strip("0")) <= 9  # float32 never needs more significant digits


@given(st.text(max_size=80))
def test_variant_parser_raises_only_its_own_error(text: str) -> None:
    with contextlib.suppress(RacError):
        parse_variant(text)


@given(st.text(alphabet=st.sampled_from(list("0123456789,()-.eE x8204:")), max_size=40))
def test_response_parser_on_protocol_like_text(text: str) -> None:
    with contextlib.suppress(RacError):
        parse_response(text)


@given(st.text(max_size=60))
def test_command_parser_raises_only_its_own_error(line: str) -> None:
    with contextlib.suppress(RacError):
        parse_command(line)


@given(
    st.one_of(
        st.binary(max_size=300),
        st.text(alphabet=string.printable, max_size=300).map(str.encode),
        st.builds(
            lambda a, b: (a + ":RC8:" + b).encode(),
            st.sampled_from(["GET", "PUT", "get", " \tPUT"]),
            st.text(alphabet="0123456789:IFDSVPJTO,.-()8 ", max_size=40),
        ),
    )
)
def test_simulator_answers_every_line_with_a_result(line: bytes) -> None:
    controller = SimulatedController(clock=lambda: 0.0)
    reply, _ = controller.handle(line.replace(b"\r", b""))
    assert reply.endswith(b"\r")
    parse_response(reply[:-1].decode("ascii"))
