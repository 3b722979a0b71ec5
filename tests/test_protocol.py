"""The pure protocol layer against the vendor's samples and the spec's decisions."""

from __future__ import annotations

from decimal import Decimal

import pytest

from rac_console.protocol import (
    MAX_FRAME,
    EncodeError,
    InputError,
    LineDecoder,
    ProtocolError,
    Variant,
    describe_hresult,
    encode_request,
    format_variant,
    get_request,
    hresult_name,
    kind_of,
    parse_response,
    parse_variant,
    put_request,
)
from rac_console.protocol.errors import FrameTooLong
from rac_console.protocol.text import describe_response, wire_text
from rac_console.protocol.variant import canonical_r4
from tests.support.samples import SAMPLES as VECTORS


@pytest.mark.parametrize("sample", VECTORS["variants"], ids=lambda s: s["text"])
def test_vendor_variants_round_trip(sample: dict) -> None:
    variant = parse_variant(sample["text"])
    assert variant.vt == sample["vt"]
    assert variant.to_json() == sample["value"]
    assert format_variant(variant) == sample["text"]


@pytest.mark.parametrize("sample", VECTORS["get"], ids=lambda s: s["request"])
def test_vendor_get_samples(sample: dict) -> None:
    kind = kind_of(sample["type"])
    assert get_request(kind, sample["index"]) == sample["request"]
    response = parse_response(sample["response"])
    assert response.code == sample["result"]
    assert response.variant is not None
    assert response.variant.vt == sample["vt"]
    assert response.variant.to_json() == sample["value"]
    assert kind.reply_problem(response.variant) is None


@pytest.mark.parametrize("sample", VECTORS["put"], ids=lambda s: s["request"])
def test_vendor_put_samples(sample: dict) -> None:
    kind = kind_of(sample["type"])
    typed = sample["value"]
    if isinstance(typed, list):
        text = " ".join(str(v) for v in typed)
    elif isinstance(typed, bool):
        text = "on" if typed else "off"
    else:
        text = str(typed)
    variant = kind.value_from_text(text)
    assert variant.vt == sample["vt"]
    assert put_request(kind, sample["index"], format_variant(variant)) == sample["request"]
    assert parse_response(sample["response"]).code == sample["result"]


@pytest.mark.parametrize("sample", VECTORS["results"], ids=lambda s: s["text"])
def test_result_codes_in_every_notation(sample: dict) -> None:
    response = parse_response(sample["text"])
    assert response.code == sample["code"]
    assert hresult_name(response.code) == sample["name"]
    if sample["name"] is None:
        assert "user-defined" in describe_hresult(response.code)


def test_spaces_around_fields_are_accepted_on_receive() -> None:
    response = parse_response("0, 3, 123")
    assert response.variant == Variant(3, 123)
    assert parse_response(" 0 ,\t8196, 1 , 2,3").variant == Variant(8196, [1.0, 2.0, 3.0])


def test_scalar_string_keeps_commas_and_array_splits() -> None:
    assert parse_variant("8,a,b,c").value == "a,b,c"
    assert parse_variant("8200,a,b,c").value == ["a", "b", "c"]
    assert parse_variant("8,").value == ""


def test_nested_variants_match_parentheses_by_depth() -> None:
    variant = parse_variant("8204,(8,a,b),(8204,(2,1))")
    assert variant.value == [Variant(8, "a,b"), Variant(8204, [Variant(2, 1)])]
    assert format_variant(variant) == "8204,(8,a,b),(8204,(2,1))"


@pytest.mark.parametrize(
    "text",
    [
        "",
        "x,1",
        "9,1",
        "3,",
        "3,1.5",
        "3,abc",
        "3,1,2",
        "2,40000",
        "17,-1",
        "4,1e39",
        "5,nan",
        "11,maybe",
        "12,8,a",
        "12,(8,a",
        "8204,(8,a",
        "8204,8,a)",
        "0,x",
        "6,1.23456",
        "3,1_000",
    ],
)
def test_malformed_variants_raise_protocol_error(text: str) -> None:
    with pytest.raises(ProtocolError):
        parse_variant(text)


def test_floats_are_written_in_shortest_round_trip_form() -> None:
    assert format_variant(Variant(4, 123.01)) == "4,123.01"
    assert format_variant(Variant(4, 123.010002)) == "4,123.01"  # same float32
    assert format_variant(Variant(5, 0.1)) == "5,0.1"
    assert format_variant(Variant(8196, [1.0, 2.0, -1.0])) == "8196,1,2,-1"
    assert parse_variant("4,123.010002136").value == 123.01


def test_bool_true_is_minus_one_and_any_nonzero_reads_true() -> None:
    assert format_variant(Variant(11, True)) == "11,-1"
    assert parse_variant("11,1").value is True
    assert parse_variant("11,TRUE").value is True
    assert parse_variant("11,False").value is False


def test_currency_and_error_codes() -> None:
    assert parse_variant("6,12.3456").value == Decimal("12.3456")
    assert format_variant(Variant(6, Decimal("12.5"))) == "6,12.5"
    assert parse_variant("10,-2147024809").value == 0x80070057
    assert format_variant(Variant(10, 0x80070057)) == "10,-2147024809"


@pytest.mark.parametrize(
    "variant",
    [
        Variant(8, "a\rb"),
        Variant(8, "a\nb"),
        Variant(8200, ["a,b"]),
        Variant(8200, [""]),
        Variant(12, Variant(8, "a)")),
        Variant(3, 2**31),
        Variant(4, float("inf")),
        Variant(4, 1e39),
        Variant(11, 1),
        Variant(9, 1),
        Variant(6, Decimal("0.00001")),
    ],
    ids=repr,
)
def test_unencodable_values_are_refused(variant: Variant) -> None:
    with pytest.raises(EncodeError):
        format_variant(variant)


def test_unknown_vartype_is_named_in_the_error() -> None:
    with pytest.raises(ProtocolError, match="unsupported VARTYPE 9"):
        parse_variant("9,1")


def test_request_frame_limit_counts_the_cr() -> None:
    assert len(encode_request("x" * (MAX_FRAME - 1))) == MAX_FRAME
    with pytest.raises(InputError, match="257 bytes"):
        encode_request("x" * MAX_FRAME)
    with pytest.raises(InputError, match="CR or LF"):
        encode_request("GET:RC8:1:I:\r")
    with pytest.raises(InputError, match="ASCII"):
        encode_request("PUT:RC8:1:S:8,é")


def test_typed_values_per_variable_type() -> None:
    assert kind_of("p").value_from_text("1 2 3 4 5 6 -1") == Variant(8196, [1, 2, 3, 4, 5, 6, -1])
    assert kind_of("V").value_from_text("1,2,3") == Variant(8196, [1.0, 2.0, 3.0])
    assert kind_of("IO").value_from_text("ON") == Variant(11, True)
    assert kind_of("IO").value_from_text("false") == Variant(11, False)
    assert kind_of("S").value_from_text('"  padded "') == Variant(8, "  padded ")
    assert kind_of("I").value_from_text("0x10") == Variant(3, 16)
    with pytest.raises(InputError, match="J needs 8 values: J1 J2 J3 J4 J5 J6 J7 J8, got 2"):
        kind_of("J").value_from_text("1 2")
    with pytest.raises(InputError, match="use one of I F D S V P J T IO"):
        kind_of("Q")


def test_field_labels_for_display() -> None:
    assert [label for label, _ in kind_of("P").fields(Variant(8196, [0.0] * 7))] == [
        "X",
        "Y",
        "Z",
        "Rx",
        "Ry",
        "Rz",
        "Fig",
    ]
    assert kind_of("T").labels[-1] == "Fig" and kind_of("T").count == 10
    assert kind_of("IO").fields(Variant(11, True)) == [("", "ON")]


def test_reply_that_cannot_belong_to_a_get_is_named() -> None:
    assert kind_of("P").reply_problem(Variant(3, 5)) is not None
    assert kind_of("P").reply_problem(Variant(8196, [1.0, 2.0, 3.0])) is not None
    assert kind_of("S").reply_problem(Variant(3, 5)) is not None
    assert kind_of("I").reply_problem(Variant(3, 5)) is None


def test_describe_response_and_wire_text() -> None:
    assert describe_response(parse_response("0,3,123")) == "S_OK  VT_I4  123"
    assert describe_response(parse_response("0x80070057")) == (
        "E_INVALIDARG 0x80070057: invalid argument"
    )
    assert wire_text(b"0,3,1\r") == "0,3,1↵"
    assert wire_text(b"\xff\x00a\\") == "\\xff\\x00a\\\\"


FRAMES = [b"0,3,123", b"0,8196,1,2,3", b"-2147024809"]


@pytest.mark.parametrize("chunking", ["whole", "halves", "bytes"])
def test_line_decoder_reassembles_frames_however_they_are_cut(chunking: str) -> None:
    stream = b"".join(f + b"\r" for f in FRAMES)
    if chunking == "whole":
        chunks = [stream]
    elif chunking == "halves":
        chunks = [stream[: len(stream) // 2], stream[len(stream) // 2 :]]
    else:
        chunks = [stream[i : i + 1] for i in range(len(stream))]
    decoder = LineDecoder()
    frames = [frame for chunk in chunks for frame in decoder.feed(chunk)]
    assert frames == FRAMES
    assert decoder.pending == b""


def test_line_decoder_keeps_the_remainder_and_tolerates_crlf() -> None:
    decoder = LineDecoder()
    assert decoder.feed(b"junk\x00\xff\r0,3,") == [b"junk\x00\xff"]
    assert decoder.pending == b"0,3,"
    assert decoder.feed(b"1\r\n0,3,2\r") == [b"0,3,1", b"0,3,2"]


def test_line_decoder_bounds_a_line_without_cr() -> None:
    decoder = LineDecoder(max_line=16)
    decoder.feed(b"x" * 16)
    with pytest.raises(FrameTooLong):
        decoder.feed(b"x")
    assert decoder.pending == b""
    assert decoder.feed(b"ok\r") == [b"ok"]


def test_latency_summary_uses_nearest_rank_percentiles() -> None:
    from rac_console.commands.latency import summarize

    summary = summarize([n / 1000 for n in range(1, 101)], errors=2, elapsed_s=1.0)
    assert (summary.min_ms, summary.p50_ms, summary.p95_ms, summary.max_ms) == (1, 50, 95, 100)
    assert summary.avg_ms == pytest.approx(50.5)
    assert summary.requests_per_s == 102
    assert summarize([], 3, 1.0).count == 0


def test_zero_keeps_its_sign_and_r4_text_is_shortest() -> None:
    import math

    minus_zero = parse_variant("4,-0")
    assert minus_zero.vt == 4
    assert minus_zero.value == 0.0 and math.copysign(1.0, minus_zero.value) == -1.0
    assert format_variant(minus_zero) == "4,-0"
    plus_zero = parse_variant("4,0")
    assert plus_zero.value == 0.0 and math.copysign(1.0, plus_zero.value) == 1.0
    assert format_variant(Variant(4, 0.0)) == "4,0"
    assert format_variant(Variant(8196, [0.0, 0.0])) == "8196,0,0"
    assert format_variant(Variant(4, canonical_r4(2.0**-96))) == "4,1.2621775e-29"


def test_huge_numbers_and_deep_nesting_are_protocol_errors() -> None:
    for text in ("3," + "9" * 5000, "9" * 5000 + ",1", "12," + "(12," * 5000 + "(3,1)"):
        with pytest.raises(ProtocolError):
            parse_variant(text)
    with pytest.raises(InputError):
        kind_of("I").value_from_text("9" * 5000)
