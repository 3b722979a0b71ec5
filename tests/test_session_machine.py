"""SessionMachine, the session's protocol rules, driven without sockets.

In the style of a framer's tests: bytes go in as a peer might send them (whole, in
halves, byte by byte, with strays and fragments around them) and the Verdict says what
they meant: the answer to the request in flight, its parse or its problem, the lines
nobody asked for, and whether the connection must be dropped.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from rac_console.protocol import Variant, kind_of
from rac_console.protocol.request import Request, get_for, put_for, raw_request
from rac_console.protocol.vartypes import VT
from rac_console.session.machine import (
    QUOTED_BYTES,
    SessionMachine,
    Verdict,
    as_lines,
    judge,
    quoted,
)
from rac_console.session.types import MAX_REPLY_LINE

INT = kind_of("I")
POS = kind_of("P")
TEXT = kind_of("S")
NOTHING = Verdict()  # a read that completed nothing and broke nothing


def machine(max_line: int = MAX_REPLY_LINE) -> SessionMachine:
    return SessionMachine(max_line)


def whole(data: bytes) -> list[bytes]:
    return [data]


def halves(data: bytes) -> list[bytes]:
    middle = len(data) // 2
    return [data[:middle], data[middle:]]


def byte_by_byte(data: bytes) -> list[bytes]:
    return [data[n : n + 1] for n in range(len(data))]


SPLITS: dict[str, Callable[[bytes], list[bytes]]] = {
    "whole": whole,
    "halves": halves,
    "byte-by-byte": byte_by_byte,
}


def feed_all(session: SessionMachine, chunks: list[bytes]) -> list[Verdict]:
    return [session.feed(chunk) for chunk in chunks]


# ------------------------------------------------------------- begin


def test_begin_gives_the_request_bytes_and_puts_it_in_flight() -> None:
    session = machine()
    assert session.in_flight is None
    request = get_for(INT, 10)
    assert session.begin(request) == b"GET:RC8:10:I:\r"
    assert session.in_flight is request
    assert session.pending == b""
    assert not session.holds_stray()


# ------------------------------------------------------------- replies


REPLIES = [
    (get_for(INT, 10), b"0,3,123\r", Variant(VT.I4, 123)),
    (get_for(POS, 10), b"0,8196,1,2,3,4,5,6,-1\r", Variant(8196, [1, 2, 3, 4, 5, 6, -1])),
    (get_for(TEXT, 10), b"0,8,Sample,Test\r", Variant(VT.BSTR, "Sample,Test")),
    (put_for(INT, 10, "3,7"), b"0\r", None),
    (raw_request("GET:RC8:10:I:"), b"0,3,5\r", Variant(VT.I4, 5)),
]


@pytest.mark.parametrize("split", SPLITS, ids=list(SPLITS))
@pytest.mark.parametrize(("request_", "reply", "value"), REPLIES, ids=["I", "P", "S", "PUT", "raw"])
def test_a_reply_is_answered_however_it_is_split(
    split: str, request_: Request, reply: bytes, value: Variant | None
) -> None:
    session = machine()
    session.begin(request_)
    *before, last = feed_all(session, SPLITS[split](reply))
    assert all(verdict == NOTHING for verdict in before)  # nothing until the CR
    assert last.answer == reply[:-1]
    assert last.response is not None
    assert last.response.ok
    assert last.response.variant == value
    assert last.problem is None
    assert last.strays == ()
    assert last.too_long is None
    assert not last.drop
    assert session.in_flight is None
    assert session.pending == b""


def test_an_error_reply_answers_a_get_without_a_problem() -> None:
    session = machine()
    session.begin(get_for(POS, 10))
    verdict = session.feed(b"0x80070057\r")
    assert verdict.answer == b"0x80070057"
    assert verdict.response is not None and not verdict.response.ok
    assert verdict.response.name == "E_INVALIDARG"
    assert verdict.problem is None and not verdict.drop


def test_one_request_takes_one_answer_and_the_next_request_its_own() -> None:
    session = machine()
    for index in range(1, 4):
        session.begin(get_for(INT, index))
        verdict = session.feed(b"0,3,%d\r" % index)
        assert verdict.answer == b"0,3,%d" % index
        assert not verdict.drop


# ------------------------------------------------------------- strays


def test_two_lines_in_the_reply_s_read_are_not_taken_for_an_answer() -> None:
    """Either may be the answer (a late stray, then the reply): the request fails."""
    session = machine()
    session.begin(get_for(INT, 1))
    verdict = session.feed(b"0,3,1\r0,3,999\r")
    assert verdict.answer == b"0,3,1"
    assert verdict.problem is not None and "more than one line" in verdict.problem
    assert verdict.strays == (b"0,3,999\r",)
    assert verdict.drop


def test_two_replies_to_one_request_only_the_first_answers() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    verdict = session.feed(b"0,3,1\r0,3,1\r0,3,2\r")
    assert verdict.answer == b"0,3,1"
    assert verdict.strays == (
        b"0,3,1\r",
        b"0,3,2\r",
    )
    assert verdict.drop


def test_a_partial_line_left_after_the_answer_is_a_stray() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    verdict = session.feed(b"0,3,1\r0,3,9")
    assert verdict.answer == b"0,3,1"
    assert verdict.problem is not None and "more than one line" in verdict.problem
    assert verdict.strays == (b"0,3,9",)  # never let it prefix the next reply
    assert verdict.drop


@pytest.mark.parametrize(
    ("data", "strays"),
    [
        (b"0,3,777\r", [b"0,3,777\r"]),
        (b"0,3,1\r0,3,2\r", [b"0,3,1\r", b"0,3,2\r"]),
        (b"0,3,42", [b"0,3,42"]),
        (b"\xff", [b"\xff"]),
    ],
    ids=["line", "two-lines", "fragment", "byte"],
)
def test_bytes_with_nothing_in_flight_are_strays(data: bytes, strays: list[bytes]) -> None:
    session = machine()
    verdict = session.feed(data)
    assert verdict.answer is None
    assert verdict.response is None and verdict.problem is None
    assert list(verdict.strays) == strays
    assert verdict.drop


def test_a_stray_after_an_answered_request_is_a_stray() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    assert session.feed(b"0,3,1\r").answer == b"0,3,1"
    verdict = session.feed(b"0,3,1\r")  # the same answer again, in a later read
    assert verdict.answer is None
    assert verdict.strays == (b"0,3,1\r",)
    assert verdict.drop


def test_an_abandoned_request_takes_no_answer() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    session.abandon()  # timed out: a late reply must not answer anything
    assert session.in_flight is None
    verdict = session.feed(b"0,3,1\r")
    assert verdict.answer is None
    assert verdict.strays == (b"0,3,1\r",)
    assert verdict.drop


def test_reset_forgets_the_request_and_the_bytes_held() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    assert session.feed(b"0,3,") == NOTHING
    assert session.pending == b"0,3,"
    assert session.holds_stray()  # bytes of a line begun
    session.reset()  # a new connection
    assert session.in_flight is None
    assert session.pending == b""
    assert not session.holds_stray()
    verdict = session.feed(b"5\r")  # the old connection's rest cannot answer anything
    assert verdict.answer is None
    assert verdict.strays == (b"5\r",)
    assert verdict.drop


# ------------------------------------------------------------- CRLF peers


def test_a_crlf_reply_in_one_read_is_answered_and_its_lf_is_harmless() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    verdict = session.feed(b"0,3,1\r\n")
    assert verdict.answer == b"0,3,1"
    assert verdict.strays == () and not verdict.drop
    assert session.pending == b"\n"
    assert not session.holds_stray()  # an LF after a CR is not a stray
    session.begin(get_for(INT, 2))
    verdict = session.feed(b"0,3,2\r\n")
    assert verdict.answer == b"0,3,2"  # the held LF does not prefix the next reply
    assert verdict.response is not None and verdict.response.variant == Variant(VT.I4, 2)
    assert not verdict.drop


def test_the_lf_of_a_crlf_reply_alone_in_the_next_read_is_harmless() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    assert session.feed(b"0,3,1\r").answer == b"0,3,1"
    assert session.feed(b"\n") == NOTHING  # nothing in flight, and still no stray
    assert not session.holds_stray()
    session.begin(get_for(INT, 2))
    verdict = session.feed(b"0,3,2\r")
    assert verdict.answer == b"0,3,2"
    assert not verdict.drop


def test_the_lf_of_the_last_reply_read_while_the_next_request_waits_is_harmless() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    assert session.feed(b"0,3,1\r").answer == b"0,3,1"
    session.begin(get_for(INT, 2))
    assert session.feed(b"\n") == NOTHING  # not the answer, not a stray
    assert session.in_flight is not None
    verdict = session.feed(b"0,3,2\r")
    assert verdict.answer == b"0,3,2"
    assert not verdict.drop


def test_the_lf_at_the_start_of_the_next_reply_is_dropped_from_it() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    session.feed(b"0,3,1\r")
    session.begin(get_for(INT, 2))
    verdict = session.feed(b"\n0,3,2\r")
    assert verdict.answer == b"0,3,2"
    assert not verdict.drop


# ------------------------------------------------------------- lines too long


def test_a_line_too_long_with_a_request_in_flight_is_a_problem() -> None:
    session = machine(16)
    session.begin(get_for(INT, 1))
    assert session.feed(b"A" * 16) == NOTHING  # at the bound: still a line begun
    verdict = session.feed(b"A" * 4)
    assert verdict.answer is None
    assert verdict.response is None
    assert verdict.problem is not None and "no CR within 16 bytes" in verdict.problem
    assert verdict.too_long == b"A" * 4  # the tail of this read, for the log
    assert verdict.strays == ()
    assert verdict.drop
    assert session.in_flight is None
    assert session.pending == b""  # nothing of it is held


def test_the_tail_of_a_line_too_long_is_bounded() -> None:
    session = machine(16)
    session.begin(get_for(INT, 1))
    verdict = session.feed(b"B" + b"A" * 1000)
    assert verdict.too_long == b"A" * 256
    assert verdict.drop and verdict.problem is not None


def test_a_line_too_long_with_nothing_in_flight_drops_without_a_problem() -> None:
    session = machine(16)
    verdict = session.feed(b"A" * 17)
    assert verdict.answer is None
    assert verdict.problem is None  # no request to fail
    assert verdict.too_long == b"A" * 17
    assert verdict.drop


def test_a_line_too_long_after_the_answer_keeps_the_answer_and_drops() -> None:
    session = machine(16)
    session.begin(get_for(INT, 1))
    verdict = session.feed(b"0,3,1\r" + b"A" * 17)
    assert verdict.answer == b"0,3,1"
    assert verdict.response is not None and verdict.response.variant == Variant(VT.I4, 1)
    assert verdict.problem is None
    assert verdict.too_long is not None
    assert verdict.drop


# ------------------------------------------------------------- replies refused


@pytest.mark.parametrize(
    ("request_", "reply", "problem"),
    [
        (get_for(POS, 1), b"0,3,5\r", None),
        (get_for(INT, 1), b"0\r", "S_OK with no value"),
        (put_for(INT, 1, "3,5"), b"0,3,5\r", "a PUT reply carries no value"),
        (get_for(INT, 1), b"0,8,text\r", None),
    ],
    ids=["P-got-I", "I-got-none", "PUT-got-value", "I-got-S"],
)
def test_a_reply_that_fails_its_check_is_a_problem(
    request_: Request, reply: bytes, problem: str | None
) -> None:
    session = machine()
    session.begin(request_)
    verdict = session.feed(reply)
    assert verdict.answer == reply[:-1]  # it came, and it was the answer
    assert verdict.response is not None  # parsed once, then refused
    assert verdict.problem
    if problem is not None:
        assert verdict.problem == problem
    assert verdict.strays == ()
    assert verdict.drop
    assert session.in_flight is None


@pytest.mark.parametrize(
    "reply",
    [b"banana\r", b"0,99,1\r", b"0,3,abc\r", b"\r", b"\xff\xfe garbage\r", b"0,8204,(8,a\r"],
    ids=["word", "unknown-vt", "bad-int", "empty", "binary", "unbalanced"],
)
def test_an_unparsable_reply_is_a_problem(reply: bytes) -> None:
    session = machine()
    session.begin(raw_request("GET:RC8:1:I:"))  # no check: only the parse can refuse it
    verdict = session.feed(reply)
    assert verdict.answer == reply[:-1]
    assert verdict.response is None
    assert verdict.problem
    assert verdict.drop
    assert session.in_flight is None


# ------------------------------------------------------------- what waited


def test_waiting_lf_on_an_open_connection_is_kept() -> None:
    session = machine()
    verdict = session.waiting_verdict(b"\n", still_open=True)
    assert verdict == NOTHING
    assert not verdict.drop


def test_a_held_lf_with_nothing_more_waiting_is_kept_and_cleared() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    session.feed(b"0,3,1\r\n")
    assert session.pending == b"\n"
    assert session.waiting_verdict(b"", still_open=True) == NOTHING
    assert session.pending == b""


@pytest.mark.parametrize(
    ("data", "still_open", "strays"),
    [
        (b"\n", False, []),  # the LF, then EOF: the connection is gone all the same
        (b"", False, []),  # EOF (or a reset) alone
        (b"0,3,1\r", True, [b"0,3,1\r"]),
        (b"\n0,3,1\r", True, [b"0,3,1\r"]),  # a CRLF's LF is not logged
        (b"0,3,1\r0,3,2\r0,3", True, [b"0,3,1\r", b"0,3,2\r", b"0,3"]),
        (b"\n\n", True, [b"\n\n"]),  # more than the LF of one CRLF
    ],
    ids=["lf-then-eof", "eof", "line", "lf-and-line", "lines-and-fragment", "two-lfs"],
)
def test_anything_else_waiting_drops(data: bytes, still_open: bool, strays: list[bytes]) -> None:
    session = machine()
    verdict = session.waiting_verdict(data, still_open)
    assert verdict.answer is None
    assert list(verdict.strays) == strays
    assert verdict.drop


def test_what_waits_is_read_after_what_is_held() -> None:
    session = machine()
    session.begin(get_for(INT, 1))
    session.feed(b"0,3,1\r\n")
    verdict = session.waiting_verdict(b"0,3,2\r", still_open=True)
    assert verdict.strays == (b"0,3,2\r",)
    assert verdict.drop


# ------------------------------------------------------------- helpers


def test_judge_parses_once_and_says_why_a_reply_cannot_answer() -> None:
    response, problem = judge(get_for(INT, 1), b"0,3,5")
    assert response is not None and response.variant == Variant(VT.I4, 5) and problem is None
    response, problem = judge(get_for(POS, 1), b"0,3,5")
    assert response is not None and problem
    response, problem = judge(get_for(INT, 1), b"banana")
    assert response is None and problem


def test_quoted_escapes_and_cuts_long_replies() -> None:
    assert quoted(b"\xff\xfe garbage") == "\\xff\\xfe garbage"
    long = b"A" * (QUOTED_BYTES + 10)
    text = quoted(long)
    assert text.startswith("A" * QUOTED_BYTES) and f"({len(long)} bytes)" in text
    assert "A" * (QUOTED_BYTES + 1) not in text


def test_as_lines_splits_waiting_bytes_as_the_log_shows_lines() -> None:
    assert as_lines(b"a\rb\rc") == [b"a\r", b"b\r", b"c"]
    assert as_lines(b"a\r\nb\r\n") == [b"a\r", b"b\r"]
    assert as_lines(b"") == []
    assert as_lines(b"\n") == []
