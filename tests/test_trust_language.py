"""Commands do what was typed, or say why not (the shared command language)."""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.commands.language import Put, Unwatch, Watch
from rac_console.engine.commands.builtin import parse_command
from rac_console.protocol import InputError
from tests.support.drivers import FrameTap, make_app, results_text, type_line, until


def put_value(line: str) -> str:
    command = parse_command(line)
    assert isinstance(command, Put)
    return command.wire


@pytest.mark.parametrize(
    ("line", "wire"),
    [
        ('put S 10 ""', "PUT:RC8:10:S:8,"),
        ("put S 10 hello world", "PUT:RC8:10:S:8,hello world"),
        ('put S 10 "  two  "', "PUT:RC8:10:S:8,  two  "),
        ("put S 10 'say \"hi\"'", 'PUT:RC8:10:S:8,say "hi"'),
        ('put S 10 he said "hi"', 'PUT:RC8:10:S:8,he said "hi"'),
    ],
)
def test_strings_are_written_as_typed(line: str, wire: str) -> None:
    assert put_value(line) == wire


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("put S 10", 'write "" for an empty string'),
        ("put S 10   ", 'write "" for an empty string'),
        ('put S 10 "a" "b"', "a string in quotes is one value"),
        ('put S 10 "unclosed', "a string in quotes is one value"),
    ],
)
def test_strings_that_would_be_guessed_are_refused(line: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        parse_command(line)


def test_watch_takes_several_variables() -> None:
    command = parse_command("watch P 0 J 0")
    assert isinstance(command, Watch)
    assert [str(v) for v in command.vars] == ["P0", "J0"]
    assert command.label == ""
    command = parse_command("watch IO 128-129 I 3 every 0.2")
    assert isinstance(command, Watch)
    assert [str(v) for v in command.vars] == ["IO128", "IO129", "I3"]
    assert command.every == 0.2
    command = parse_command('watch P 0 "J 0 side"')
    assert isinstance(command, Watch)
    assert [str(v) for v in command.vars] == ["P0"] and command.label == "J 0 side"
    command = parse_command('watch P 0 "check every 5" every 2')
    assert isinstance(command, Watch)
    assert command.label == "check every 5" and command.every == 2
    command = parse_command("watch IO 128-135 gripper bank")
    assert isinstance(command, Watch) and command.label == "gripper bank"
    with pytest.raises(InputError, match="a label names one variable or range"):
        parse_command("watch P 0 J 0 home")
    command = parse_command("unwatch P 0 J 0")
    assert isinstance(command, Unwatch) and [str(v) for v in command.vars] == ["P0", "J0"]
    with pytest.raises(InputError, match="unwatch takes variables only"):
        parse_command("unwatch P 0 garbage words here")
    for bad in ("watch I 1 every nan", "watch I 1 every inf", "watch I 1 every -1"):
        with pytest.raises(InputError, match="every must be from 0"):
            parse_command(bad)


@pytest.mark.slow
async def test_watch_every_polls_those_rows_only_and_leaves_the_interval(tmp_path: Path) -> None:
    app = make_app(tmp_path, interval=0.05)
    async with app.run_test(size=(120, 40)) as pilot:
        tap = FrameTap(tmp_path)
        await type_line(pilot, "watch I 5")
        await type_line(pilot, "watch IO 3 every 60")
        await until(pilot, lambda: "polled every 60 s" in results_text(app), "the answer")
        assert app.main_screen.status is not None and app.main_screen.status.interval == 0.05
        await until(pilot, lambda: tap.sent.count(b"GET:RC8:5:I:\r") >= 10, "ten polls of I5")
        assert tap.sent.count(b"GET:RC8:3:IO:\r") == 1  # once, then not for a minute


@pytest.mark.slow
async def test_unwatch_of_an_unwatched_variable_says_so(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await type_line(pilot, "unwatch IO 7")
        await until(pilot, lambda: "IO7 not watched" in results_text(app), "the answer")
        await type_line(pilot, "watch IO 4-5")
        await type_line(pilot, "unwatch IO 4-7")
        await until(pilot, lambda: "stopped watching 2 variables" in results_text(app), "unwatch")
        assert "IO6..IO7 (2 variables) were not watched" in results_text(app)
        await type_line(pilot, "watch P 0 J 0")
        await until(pilot, lambda: "watching P0, J0" in results_text(app), "both watched")
        assert {str(v) for v in app.main_screen.members.rows} == {"P0", "J0"}


@pytest.mark.parametrize("line", ["put S 10 a\tb", "put S 10 bell\x07", "put S 10 \x1b[2J"])
def test_control_characters_in_a_string_are_refused_before_sending(line: str) -> None:
    with pytest.raises(InputError, match="control character"):
        parse_command(line)
