"""A mistyped command or type is answered with the closest word, in the pure parser,
so the console, the REPL, ``run`` and the one-shot CLI all say it alike (issue 20)."""

from __future__ import annotations

import pytest

from rac_console.engine.commands.builtin import parse_command
from rac_console.protocol import InputError
from rac_console.protocol.text import close_match


def refused(line: str) -> str:
    with pytest.raises(InputError) as caught:
        parse_command(line)
    return str(caught.value)


@pytest.mark.parametrize(
    ("line", "meant"),
    [("gte I 1", "get"), ("pit I 1 2", "put"), ("wacth I 0", "watch"), ("Conect sim", "connect")],
)
def test_a_mistyped_command_names_the_closest_one(line: str, meant: str) -> None:
    word = line.split()[0].lower()
    message = refused(line)
    assert message.startswith(f"unknown command {word!r}: did you mean {meant}?"), message
    assert "type help for the list" in message  # the way to the whole list stays


@pytest.mark.parametrize("line", ["bogus", "5", "xyzzy I 1"])
def test_a_word_like_no_command_suggests_nothing(line: str) -> None:
    message = refused(line)
    assert "did you mean" not in message
    assert "type help for the list" in message


@pytest.mark.parametrize(
    ("line", "meant"), [("get IOO 1", "IO"), ("watch pp 0", "P"), ("put IIO 3 on", "IO")]
)
def test_a_mistyped_type_names_the_closest_one(line: str, meant: str) -> None:
    message = refused(line)
    assert f"did you mean {meant}?" in message, message
    assert "I F D S V P J T IO" in message


def test_a_type_close_to_none_lists_them_without_a_guess() -> None:
    message = refused("get X 1")
    assert "unknown variable type 'X'" in message
    assert "did you mean" not in message
    assert "I F D S V P J T IO" in message


def test_close_match_is_case_blind_and_keeps_the_choice_as_written() -> None:
    assert close_match("GTE", ["get", "put"]) == "get"
    assert close_match("ioo", ["I", "IO"]) == "IO"
    assert close_match("zzz", ["get", "put"]) is None
    assert close_match("", ["get"]) is None
