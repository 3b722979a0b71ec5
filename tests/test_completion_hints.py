"""What the console and the REPL offer at the cursor: completions and grey hints."""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.present.completion import (
    WHOLE_LIST,
    Candidate,
    common_prefix,
    complete,
    hint,
    shown_candidates,
)

COMMAND_NAMES = [
    "get",
    "put",
    "send",
    "watch",
    "unwatch",
    "interval",
    "pause",
    "resume",
    "connect",
    "use",
    "disconnect",
    "save",
    "load",
    "frames",
    "latency",
    "wait",
    "log",
    "publish",
    "record",
    "transcript",
    "clear",
    "help",
    "quit",
]
TYPE_CODES = ["I", "F", "D", "S", "V", "P", "J", "T", "IO"]
SEEN = [("I", 3), ("I", 1), ("P", 0), ("IO", 128), ("I", 3), ("S", 12)]


def texts(text: str, seen: list[tuple[str, int]] = SEEN) -> list[str]:
    return [c.text for c in complete(text, seen)]


# ------------------------------------------------------------------ command names


def test_an_empty_line_offers_every_command_with_its_summary() -> None:
    candidates = complete("")
    assert [c.text for c in candidates] == COMMAND_NAMES
    assert all(c.start == 0 and c.help for c in candidates)
    assert {c.text: c.help for c in candidates}["get"] == "read a variable"


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("g", ["get"]),
        ("GE", ["get"]),
        ("p", ["put", "pause", "publish"]),
        ("dis", ["disconnect"]),
        ("l", ["load", "latency", "log"]),
        ("x", []),
        ("getx", []),
    ],
)
def test_command_names_complete_from_what_is_typed(text: str, expected: list[str]) -> None:
    candidates = complete(text)
    assert [c.text for c in candidates] == expected
    assert all(c.start == len(text) for c in candidates)  # the typed word is replaced


def test_help_completes_command_names() -> None:
    assert texts("help ") == COMMAND_NAMES
    candidates = complete("help pu")
    assert [(c.text, c.start) for c in candidates] == [("put", 2), ("publish", 2)]
    assert texts("help put ") == []


# ------------------------------------------------------------------ types and indices


@pytest.mark.parametrize("command", ["get", "put", "watch"])
def test_a_variable_command_offers_the_types(command: str) -> None:
    candidates = complete(f"{command} ")
    assert [c.text for c in candidates] == TYPE_CODES
    assert {c.text: c.help for c in candidates}["P"] == "position"
    assert {c.text: c.help for c in candidates}["IO"] == "I/O bit"


def test_unwatch_also_offers_all() -> None:
    assert texts("unwatch ") == [*TYPE_CODES, "all"]
    assert texts("unwatch A") == ["all"]
    assert texts("unwatch ALL") == ["all"]


@pytest.mark.parametrize(
    ("typed", "expected"),
    [("i", ["I", "IO"]), ("I", ["I", "IO"]), ("io", ["IO"]), ("t", ["T"]), ("Q", [])],
)
def test_a_type_completes_from_its_first_letters(typed: str, expected: list[str]) -> None:
    candidates = complete(f"get {typed}")
    assert [c.text for c in candidates] == expected
    assert all(c.start == len(typed) for c in candidates)


def test_indices_seen_are_offered_for_that_type_only_sorted_and_once() -> None:
    candidates = complete("get I ", SEEN)
    assert [(c.text, c.help, c.start) for c in candidates] == [("1", "I1", 0), ("3", "I3", 0)]
    assert texts("watch io ") == ["128"]
    assert texts("put S ") == ["12"]
    assert texts("get J ") == []
    assert texts("get I ", []) == []


def test_an_index_being_typed_narrows_the_candidates() -> None:
    seen = [("I", 1), ("I", 10), ("I", 12), ("I", 2)]
    candidates = complete("get I 1", seen)
    assert [c.text for c in candidates] == ["1", "10", "12"]
    assert all(c.start == 1 for c in candidates)
    assert texts("get I 12", seen) == ["12"]


def test_nothing_is_offered_after_the_variable_of_a_get() -> None:
    assert texts("get I 1 ") == []
    assert texts("get I1 ") == []
    assert texts("get P[0] ") == []
    assert texts("get Q ") == []


# ------------------------------------------------------------------ values


@pytest.mark.parametrize("text", ["put IO 3 ", "put io 128 ", "put IO3 ", "put IO[3] "])
def test_put_of_an_io_bit_offers_on_and_off(text: str) -> None:
    candidates = complete(text)
    assert [c.text for c in candidates] == ["on", "off"]
    assert "11,-1" in candidates[0].help and "11,0" in candidates[1].help


def test_on_and_off_complete_from_what_is_typed() -> None:
    assert [(c.text, c.start) for c in complete("put IO 3 of")] == [("off", 2)]
    assert texts("put IO 3 o") == ["on", "off"]


def test_other_puts_offer_no_value() -> None:
    assert texts("put I 3 ") == []
    assert texts("put P 0 ") == []
    assert texts("put IO 3 on ") == []


def test_frames_offers_on_and_off() -> None:
    assert texts("frames ") == ["on", "off"]
    assert texts("frames of") == ["off"]
    assert texts("frames on ") == []


@pytest.mark.parametrize("text", ["interval ", "latency ", "save ", "pause ", "bogus "])
def test_commands_without_choices_offer_nothing(text: str) -> None:
    assert complete(text, SEEN) == []


# ------------------------------------------------------------------ raw lines


@pytest.mark.parametrize("text", ["GET:", "GET:RC8", "put:RC8:1:IO:", "  PUT:RC8:3:I:"])
def test_raw_lines_get_no_completion_and_no_hint(text: str) -> None:
    assert complete(text, SEEN) == []
    assert hint(text + " ") == ""


def test_get_without_colon_is_still_the_get_command() -> None:
    assert texts("GET ") == TYPE_CODES
    assert hint("GET ") == "TYPE INDEX"


# ------------------------------------------------------------------ hints


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("get ", "TYPE INDEX"),
        ("  get\t", "TYPE INDEX"),
        ("get I ", "INDEX"),
        ("get I 1 ", ""),
        ("get I1 ", ""),
        ("get P[3] ", ""),
        ("put ", "TYPE INDEX VALUE..."),
        ("put I ", "INDEX INTEGER"),
        ("put I 1 ", "INTEGER"),
        ("put F 1 ", "NUMBER"),
        ("put D 1 ", "NUMBER"),
        ("put S 1 ", "TEXT"),
        ("put IO 1 ", "on|off"),
        ("put V 1 ", "X Y Z"),
        ("put P ", "INDEX X Y Z Rx Ry Rz Fig"),
        ("put P 1 ", "X Y Z Rx Ry Rz Fig"),
        ("put P[1] 10 ", "Y Z Rx Ry Rz Fig"),
        ("put P 1 1 2 3 4 5 6 ", "Fig"),
        ("put P 1 1 2 3 4 5 6 7 ", ""),
        ("put J 1 ", "J1 J2 J3 J4 J5 J6 J7 J8"),
        ("put T 1 1 2 3 ", "Ox Oy Oz Ax Ay Az Fig"),
        ("put I 1 5 ", ""),
        ("watch ", "TYPE INDEX [LABEL] [every SECONDS]"),
        ("watch I 1 ", "[LABEL] [every SECONDS]"),
        ("watch IO 128-135 ", "[LABEL] [every SECONDS]"),
        ("watch I 1 gripper ", "[every SECONDS]"),
        ("unwatch ", "TYPE INDEX | all"),
        ("interval ", "SECONDS"),
        ("connect ", "HOST[:PORT]"),
        ("connect rc8 ", ""),
        ("save ", "FILE"),
        ("load ", "FILE"),
        ("frames ", "on|off"),
        ("latency ", "[COUNT] [TYPE INDEX]"),
        ("latency 100 ", "[TYPE INDEX]"),
        ("help ", "[COMMAND]"),
        ("help put ", ""),
        ("pause ", ""),
        ("quit ", ""),
    ],
)
def test_the_hint_shows_what_the_command_still_needs(text: str, expected: str) -> None:
    assert hint(text) == expected


@pytest.mark.parametrize("text", ["", "get", "get I", "put IO 3 o", "bogus ", "get Q ", "   "])
def test_no_hint_while_a_word_is_typed_or_for_unknown_words(text: str) -> None:
    assert hint(text) == ""


@pytest.mark.parametrize(
    ("text", "expected"),
    [("latency 100 I ", "INDEX"), ("latency I ", "INDEX"), ("latency I 5 ", "")],
)
def test_latency_hint_follows_the_typed_variable(text: str, expected: str) -> None:
    assert hint(text) == expected


@pytest.mark.parametrize(
    ("text", "expected"), [("watch I 1 every 2 ", ""), ("watch I 1 every ", "SECONDS")]
)
def test_watch_hint_after_every(text: str, expected: str) -> None:
    assert hint(text) == expected


# ------------------------------------------------------------------ common prefix


def test_common_prefix_of_candidates() -> None:
    assert common_prefix([]) == ""
    assert common_prefix(complete("get I")) == "I"
    assert common_prefix(complete("g")) == "get"
    assert common_prefix(complete("frames ")) == "o"
    assert common_prefix(complete("unwatch ")) == ""
    mixed = [Candidate("Pause", "", 0), Candidate("put", "", 0)]
    assert common_prefix(mixed) == "P"  # case-insensitive, spelled as the first


# ------------------------------------------------------------------ how much is listed


def test_a_short_list_is_shown_whole() -> None:
    """The 9 types were listed as 6 and "… and 3 more" (issue 20)."""
    types = complete("get ")
    assert shown_candidates(types) == (types, 0)
    waits = complete("wait I 1 ")
    assert len(waits) == 7 and shown_candidates(waits) == (waits, 0)
    exactly = [Candidate(str(n), "", 0) for n in range(WHOLE_LIST)]
    assert shown_candidates(exactly) == (exactly, 0)
    assert WHOLE_LIST >= 12


def test_a_long_list_is_cut_leaving_a_line_to_say_how_many_more() -> None:
    commands = complete("")
    shown, more = shown_candidates(commands)
    assert shown == commands[: WHOLE_LIST - 1]
    assert len(commands) > WHOLE_LIST and len(shown) + more == len(commands)


@pytest.mark.slow  # over half a second
async def test_the_console_lists_the_nine_types_whole(tmp_path: Path) -> None:
    from tests.support.drivers import make_app, until

    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press(*"get ")
        await pilot.press("tab")
        panel = app.main_screen.panes.completions
        await until(pilot, lambda: panel.has_class("-visible"), "the list")
        await pilot.pause()
        listed = str(panel.render())
        assert "more" not in listed
        for code in TYPE_CODES:
            assert any(line.split()[:1] == [code] for line in listed.splitlines()), code
        assert panel.size.height == len(TYPE_CODES)  # no line cut off by the panel
