"""Input colouring: the kinds of the pieces of a typed line."""

from __future__ import annotations

import pytest

from rac_console.present.tokens import tokenize

LINES = [
    "",
    "get I 10",
    "  get  I 1 ",
    "get P[3]",
    "put IO 3 on",
    "watch IO 128-135 gripper every 2",
    "unwatch all",
    "GET:RC8:1:I:",
    "bogus x y",
    "connect [::1]:5007",
    "put S 1 \t two  words ",
    "get X 1",
]


@pytest.mark.parametrize("line", LINES)
def test_the_pieces_cover_the_line_exactly(line: str) -> None:
    pieces = tokenize(line)
    assert "".join(text for _, text in pieces) == line
    assert all(text for _, text in pieces)  # no empty piece
    for kind, text in pieces:
        assert (kind == "space") == text.isspace(), (kind, text)


def test_an_empty_line_has_no_pieces() -> None:
    assert tokenize("") == []


@pytest.mark.parametrize("line", ["GET:RC8:1:I:", "put:RC8:1:I:3,5", "  PUT:junk here"])
def test_a_raw_line_is_one_raw_piece(line: str) -> None:
    assert tokenize(line) == [("raw", line)]


def test_get_with_a_spaced_index() -> None:
    assert tokenize("get I 10") == [
        ("command", "get"),
        ("space", " "),
        ("type", "I"),
        ("space", " "),
        ("index", "10"),
    ]


@pytest.mark.parametrize(
    ("word", "pieces"),
    [
        ("I10", [("type", "I"), ("index", "10")]),
        ("io128", [("type", "io"), ("index", "128")]),
        ("P[3]", [("type", "P["), ("index", "3]")]),
        ("i[1-3]", [("type", "i["), ("index", "1-3]")]),
        ("IO128-135", [("type", "IO"), ("index", "128-135")]),
    ],
)
def test_a_variable_written_as_one_word_is_split_into_type_and_index(
    word: str, pieces: list[tuple[str, str]]
) -> None:
    assert tokenize(f"watch {word}") == [("command", "watch"), ("space", " "), *pieces]


def test_what_follows_the_variable_is_a_value() -> None:
    assert tokenize("put IO3 on") == [
        ("command", "put"),
        ("space", " "),
        ("type", "IO"),
        ("index", "3"),
        ("space", " "),
        ("value", "on"),
    ]
    kinds = [kind for kind, _ in tokenize("put P 1 1 2 3 4 5 6 7") if kind != "space"]
    assert kinds == ["command", "type", "index"] + ["value"] * 7


def test_command_words_are_known_in_any_case_and_unknown_ones_are_errors() -> None:
    assert tokenize("GET")[0] == ("command", "GET")
    assert tokenize("Latency")[0] == ("command", "Latency")
    assert tokenize("gett I 1")[0] == ("error", "gett")
    assert tokenize("bogus x") == [("error", "bogus"), ("space", " "), ("value", "x")]


@pytest.mark.parametrize("word", ["X", "IOX", "12", "all"])
def test_a_word_that_is_no_type_after_get_is_an_error(word: str) -> None:
    assert tokenize(f"get {word} 1") == [
        ("command", "get"),
        ("space", " "),
        ("error", word),
        ("space", " "),
        ("index", "1"),
    ]


def test_all_after_unwatch_is_a_value() -> None:
    assert tokenize("unwatch all")[2] == ("value", "all")
    assert tokenize("unwatch All")[2] == ("value", "All")


@pytest.mark.parametrize(
    "line", ["interval 0.5", "connect rc8:5006", "save cell 3.toml", "frames on", "latency 100 I 0"]
)
def test_arguments_of_other_commands_are_values(line: str) -> None:
    pieces = [(kind, text) for kind, text in tokenize(line) if kind != "space"]
    assert pieces[0] == ("command", line.split()[0])
    assert [kind for kind, _ in pieces[1:]] == ["value"] * (len(line.split()) - 1)


def test_a_type_alone_has_no_index_piece() -> None:
    assert tokenize("get I") == [("command", "get"), ("space", " "), ("type", "I")]
