"""A request line is read once (:func:`parse_request`): its command word, its variable,
a PUT's value, and whether it is a well-formed GET or PUT."""

from __future__ import annotations

import pytest

from rac_console.protocol import KINDS, parse_request
from rac_console.protocol.request import get_for, put_for, raw_request
from rac_console.protocol.variables import MAX_INDEX


@pytest.mark.parametrize(
    ("line", "code", "index"),
    [
        ("GET:RC8:10:I:", "I", 10),
        ("GET:RC8:0:IO:", "IO", 0),
        ("GET:RC8:32767:P:", "P", MAX_INDEX),
        ("get:rc8:3:io:", "IO", 3),  # any case
        ("Get:Rc8:3:j:", "J", 3),
        ("GET:RC8:00010:I:", "I", 10),  # leading zeros, five digits at most
        (b"GET:RC8:128:IO:\r", "IO", 128),  # a frame: its CR ends it, not part of it
    ],
)
def test_a_well_formed_get(line: str | bytes, code: str, index: int) -> None:
    parsed = parse_request(line)
    assert parsed.command == "GET"
    assert parsed.var == (KINDS[code], index)
    assert parsed.value == ""
    assert parsed.is_get
    assert not parsed.is_put
    assert not parsed.writes
    assert parsed.names(code, index)
    assert not parsed.names(code, index + 1)


@pytest.mark.parametrize(
    ("line", "code", "index", "value"),
    [
        ("PUT:RC8:10:I:5", "I", 10, "5"),
        ("put:rc8:1:s:a:b,c", "S", 1, "a:b,c"),  # the value is the rest, colons and all
        ("PUT:RC8:2:F:", "F", 2, ""),
        (b"PUT:RC8:7:V:1,2,3\r", "V", 7, "1,2,3"),
    ],
)
def test_a_well_formed_put(line: str | bytes, code: str, index: int, value: str) -> None:
    parsed = parse_request(line)
    assert parsed.command == "PUT"
    assert parsed.var == (KINDS[code], index)
    assert parsed.value == value
    assert parsed.is_put
    assert parsed.writes
    assert not parsed.is_get


@pytest.mark.parametrize(
    "line",
    [
        "GET:RC8:1:I:3,5",  # a GET carrying a parameter
        "GET:RC8:1:I:\x1b",
        "GET:RC8:1:I::",
        "GET:RC8:1:I:\r",  # a text's CR is part of it (only a frame's last CR is not)
        b"GET:RC8:1:I:\r\r",
    ],
)
def test_a_get_with_anything_after_its_head_names_its_variable_but_is_not_well_formed(
    line: str | bytes,
) -> None:
    parsed = parse_request(line)
    assert parsed.command == "GET"
    assert parsed.var == (KINDS["I"], 1)
    assert not parsed.is_get


@pytest.mark.parametrize(
    ("line", "command"),
    [
        ("GET:RC8:1:X:", "GET"),  # no such type
        ("GET:RC8:32768:I:", "GET"),  # past the last index
        ("GET:RC8:000010:I:", "GET"),  # six digits
        ("GET:RC8::I:", "GET"),
        ("GET:RC8:-1:I:", "GET"),
        ("GET:RC8:1:I", "GET"),  # no colon after the type
        ("GET:RC9:1:I:", "GET"),
        (" GET:RC8:1:I:", "GET"),  # a blank before it
        ("\x01PUT:RC8:1:I:3,5", "\x01PUT"),
        ("GET :RC8:1:I:", "GET"),
        ("GET:RC8:1:ı:", "GET"),  # a dotless i is not I, though it upper-cases to one
        ("GET:RC8:١:I:", "GET"),  # an Arabic-Indic digit is not a digit of RAC
        (b"GET:RC8:1:\xff:\r", "GET"),
        ("GETS:RC8:1:I:", "GETS"),
        ("FOO", "FOO"),
        ("SIM:GET:", "SIM"),
        ("", ""),
    ],
)
def test_a_malformed_line_names_no_variable(line: str | bytes, command: str) -> None:
    parsed = parse_request(line)
    assert parsed.command == command
    assert parsed.var is None
    assert parsed.value is None
    assert not parsed.is_get
    assert not parsed.is_put


@pytest.mark.parametrize(
    ("line", "writes"),
    [
        ("PUT:RC8:1:I:5", True),
        (" PUT:RC8:1:I:5", True),  # blanks aside: a lenient controller may still write
        ("\tput:junk", True),
        ("PUTX:RC8:1:I:5", True),
        ("PUT", True),
        ("PU:T", False),
        ("GET:RC8:1:I:", False),
        ("\x01PUT:RC8:1:I:5", False),
    ],
)
def test_a_line_starting_with_put_writes_well_formed_or_not(line: str, writes: bool) -> None:
    assert parse_request(line).writes is writes
    assert raw_request(line).write is writes


def test_a_request_is_read_once_from_its_own_bytes() -> None:
    get = get_for(KINDS["IO"], 128)
    assert get.line == parse_request(get.data)
    assert get.read_only_safe and not get.write
    put = put_for(KINDS["I"], 10, "3,5")
    assert put.line.var == (KINDS["I"], 10) and put.line.value == "3,5"
    assert put.write and not put.read_only_safe
    raw = raw_request("GET:RC8:1:I:x")
    assert raw.line.var == (KINDS["I"], 1) and not raw.read_only_safe


def test_bytes_and_text_read_alike() -> None:
    for text in ("GET:RC8:1:I:", "put:rc8:3:p:1,2,3,4,5,6,7", "FOO", "GET:RC8:1:I:x"):
        assert parse_request(text) == parse_request(text.encode("ascii") + b"\r")
