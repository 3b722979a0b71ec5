"""The command language, parsed without a controller: each command gives the object
a front end acts on, and bad input gives a message that says what is wrong and how
to write it."""

from __future__ import annotations

import math
from typing import TypeVar

import pytest

from rac_console.commands.language import (
    Connect,
    Frames,
    Get,
    Help,
    Latency,
    Put,
    Raw,
    SetInterval,
    Simple,
    Step,
    Unwatch,
    Watch,
    WatchFile,
    is_raw_line,
    parse_var,
    split_word,
)
from rac_console.engine.commands.builtin import parse_command
from rac_console.protocol import InputError

C = TypeVar("C")


def parsed(line: str, cls: type[C]) -> C:
    command = parse_command(line)
    assert isinstance(command, cls), f"{line!r} gave {command!r}, not a {cls.__name__}"
    return command


def names(variables: tuple) -> list[str]:
    return [str(v) for v in variables]


def refused(line: str) -> str:
    with pytest.raises(InputError) as info:
        parse_command(line)
    return str(info.value)


# ------------------------------------------------------------------ blank lines


@pytest.mark.parametrize(
    "line", ["", "   ", "\t", "\r\n", "# a note", "   # indented note", "#get I 1"]
)
def test_blank_lines_and_comments_are_no_command(line: str) -> None:
    assert parse_command(line) is None


# ------------------------------------------------------------------ get


@pytest.mark.parametrize(
    ("line", "code", "index"),
    [
        ("get I 10", "I", 10),
        ("get i10", "I", 10),
        ("get I[10]", "I", 10),
        ("GET P[ 3 ]", "P", 3),
        ("  Get   io   128  ", "IO", 128),
        ("get IO0", "IO", 0),
        ("get S 32767", "S", 32767),
        ("get j 7\r\n", "J", 7),
    ],
)
def test_get_names_one_variable_however_it_is_spelled(line: str, code: str, index: int) -> None:
    command = parsed(line, Get)
    assert command.var.kind.code == code
    assert command.var.index == index
    assert command.wire == f"GET:RC8:{index}:{code}:"


def test_get_of_each_type_sends_that_type() -> None:
    for code in ("I", "F", "D", "S", "V", "P", "J", "T", "IO"):
        command = parsed(f"get {code.lower()} 5", Get)
        assert str(command.var) == f"{code}5"
        assert command.wire == f"GET:RC8:5:{code}:"


@pytest.mark.parametrize(
    ("line", "fragments"),
    [
        ("get", ["missing variable", "get TYPE INDEX", "get I 10"]),
        ("get I", ["I needs an index", "get TYPE INDEX"]),
        ("get X 1", ["unknown variable type 'X'", "I F D S V P J T IO"]),
        ("get I 1 2", ["only a variable", "'2'", "get I1"]),
        ("get I 99999", ["too large", "0 to 32767"]),
        ("get I -1", ["whole number from 0 to 32767", "'-1'"]),
        ("get P [3]", ["whole number", "'[3]'"]),
    ],
)
def test_a_bad_get_says_what_is_wrong_and_how_to_write_it(line: str, fragments: list[str]) -> None:
    message = refused(line)
    for fragment in fragments:
        assert fragment in message, (line, message)


# ------------------------------------------------------------------ put


@pytest.mark.parametrize(
    ("line", "code", "index", "value", "wire"),
    [
        ("put I 10 123", "I", 10, 123, "PUT:RC8:10:I:3,123"),
        ("put I 10 -5", "I", 10, -5, "PUT:RC8:10:I:3,-5"),
        ("put I 1 0x10", "I", 1, 16, "PUT:RC8:1:I:3,16"),
        ("put D 2 1e3", "D", 2, 1000.0, "PUT:RC8:2:D:5,1000"),
        ("put F 3 1.5", "F", 3, 1.5, "PUT:RC8:3:F:4,1.5"),
        ("put IO 3 on", "IO", 3, True, "PUT:RC8:3:IO:11,-1"),
        ("put io 3 OFF", "IO", 3, False, "PUT:RC8:3:IO:11,0"),
        ("put IO 3 1", "IO", 3, True, "PUT:RC8:3:IO:11,-1"),
        ("put IO 3 false", "IO", 3, False, "PUT:RC8:3:IO:11,0"),
        ("put S[4] hello world", "S", 4, "hello world", "PUT:RC8:4:S:8,hello world"),
        ("put V 2 1, 2, 3", "V", 2, [1.0, 2.0, 3.0], "PUT:RC8:2:V:8196,1,2,3"),
        (
            "put P1 1 2 3 4 5 6 7",
            "P",
            1,
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0],
            "PUT:RC8:1:P:8196,1,2,3,4,5,6,7",
        ),
    ],
)
def test_put_carries_the_typed_value_and_its_wire_text(
    line: str, code: str, index: int, value: object, wire: str
) -> None:
    command = parsed(line, Put)
    assert (command.var.kind.code, command.var.index) == (code, index)
    assert command.value.value == value
    assert type(command.value.value) is type(value)
    assert command.wire == wire
    assert command.value_text == wire.split(":", 4)[4]


@pytest.mark.parametrize("line", ["put F 1 -0", "put D 1 -0.0"])
def test_put_of_minus_zero_keeps_the_sign(line: str) -> None:
    command = parsed(line, Put)
    assert command.value.value == 0.0
    assert math.copysign(1.0, command.value.value) == -1.0
    assert command.value_text.endswith(",-0")


@pytest.mark.parametrize(
    ("line", "fragments"),
    [
        ("put", ["missing variable", "put TYPE INDEX VALUE", "put I 10 123"]),
        ("put I", ["I needs an index", "put TYPE INDEX VALUE"]),
        ("put I 1", ["I needs a value", "INTEGER"]),
        ("put I 1 abc", ["whole number", "'abc'"]),
        ("put I 1 99999999999", ["out of range for I", "2147483647"]),
        ("put IO 1 maybe", ["on or off", "'maybe'"]),
        ("put P 1 1 2", ["P needs 7 values", "X Y Z Rx Ry Rz Fig", "got 2"]),
        ("put P 1 1 2 3 4 5 6 x", ["P Fig needs a number", "'x'"]),
        ("put F 1 1e39", ["out of range for F"]),
    ],
)
def test_a_bad_put_says_what_is_wrong_and_how_to_write_it(line: str, fragments: list[str]) -> None:
    message = refused(line)
    for fragment in fragments:
        assert fragment in message, (line, message)


# ------------------------------------------------------------------ raw lines and send


@pytest.mark.parametrize(
    "line", ["GET:RC8:10:I:", "put:RC8:1:I:3,5", "  PUT:RC8:1:I:3,5", "GET:RC8:bad"]
)
def test_a_raw_line_is_sent_exactly_as_typed(line: str) -> None:
    assert parsed(line, Raw).wire == line


def test_a_raw_line_loses_only_its_line_ending() -> None:
    assert parsed("GET:RC8:1:I:\r\n", Raw).wire == "GET:RC8:1:I:"


@pytest.mark.parametrize(
    ("line", "wire"),
    [
        ("send GET:RC8:10:I:", "GET:RC8:10:I:"),
        ("send hello world", "hello world"),
        ("SEND GET:RC8:bad", "GET:RC8:bad"),
    ],
)
def test_send_sends_the_rest_of_the_line_even_malformed(line: str, wire: str) -> None:
    assert parsed(line, Raw).wire == wire


@pytest.mark.parametrize(
    ("line", "fragments"),
    [
        ("send", ["send needs the text", "send GET:RC8:10:I:"]),
        ("send " + "x" * 300, ["RAC allows at most 256"]),
        ("send caf\u00e9", ["ASCII", "'\u00e9'"]),
        ("GET:RC8:1:I:\rGET:RC8:2:I:", ["cannot contain CR or LF"]),
    ],
)
def test_a_line_that_cannot_be_sent_is_refused(line: str, fragments: list[str]) -> None:
    message = refused(line)
    for fragment in fragments:
        assert fragment in message, (line, message)


# ------------------------------------------------------------------ watch


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ("watch P 0", ["P0"]),
        ("watch IO 128-131", ["IO128", "IO129", "IO130", "IO131"]),
        ("watch IO128-130", ["IO128", "IO129", "IO130"]),
        ("watch io [4 - 6]", ["IO4", "IO5", "IO6"]),
        ("watch I[1-3]", ["I1", "I2", "I3"]),
        ("watch I 3-3", ["I3"]),
        ("watch P 0 J 0 IO 7-8", ["P0", "J0", "IO7", "IO8"]),
        ("watch I 1-3 I 2", ["I1", "I2", "I3"]),  # a variable named twice is one row
    ],
)
def test_watch_takes_variables_ranges_and_lists(line: str, expected: list[str]) -> None:
    command = parsed(line, Watch)
    assert names(command.vars) == expected
    assert command.label == ""
    assert command.every is None


def test_a_range_may_hold_256_variables_and_no_more() -> None:
    command = parsed("watch I 0-255", Watch)
    assert len(command.vars) == 256
    assert (command.vars[0].index, command.vars[-1].index) == (0, 255)
    assert "at most 256" in refused("watch I 0-256")


@pytest.mark.parametrize(
    ("line", "vars_", "label", "every"),
    [
        ("watch IO 128-129 gripper", ["IO128", "IO129"], "gripper", None),
        ("watch P 0 pick and place", ["P0"], "pick and place", None),
        ('watch P 0 "J 0 side"', ["P0"], "J 0 side", None),
        ("watch P 0 'J 0 side'", ["P0"], "J 0 side", None),
        ('watch P 0 ""', ["P0"], "", None),
        ("watch I 1 every 0.2", ["I1"], "", 0.2),
        ("watch I 1 every 0.2s", ["I1"], "", 0.2),
        ("watch I 1 every 0", ["I1"], "", 0.0),
        ("watch I 1 every 3600", ["I1"], "", 3600.0),
        ("watch I[1-2] gripper every 2", ["I1", "I2"], "gripper", 2.0),
        ('watch I 1 "poll every time" every 5', ["I1"], "poll every time", 5.0),
        ("watch P 0 J 0 every 1", ["P0", "J0"], "", 1.0),
    ],
)
def test_watch_labels_and_every(
    line: str, vars_: list[str], label: str, every: float | None
) -> None:
    command = parsed(line, Watch)
    assert names(command.vars) == vars_
    assert command.label == label
    assert command.every == every


@pytest.mark.parametrize(
    ("line", "fragments"),
    [
        ("watch", ["missing variable", "watch TYPE INDEX", "watch IO 128-135"]),
        ("watch I", ["I needs an index", "watch TYPE INDEX"]),
        ("watch Q 1", ["unknown variable type 'Q'"]),
        ("watch I 5-3", ["a range runs upwards", "I 3-5"]),
        ("watch I 1 J 2 home", ["a label names one variable or range", 'watch P 0 "J 0 side"']),
        ('watch I 1 "abc', ['closing " is missing', 'watch P 0 "pick"']),
        ('watch I 1 "lab" junk', ["only every SECONDS may follow", "'junk'"]),
        ("watch I 1 every soon", ["every needs a number of seconds", "every 0.5", "'soon'"]),
        ("watch I 1 every 3601", ["every must be from 0 to 3600 seconds"]),
        ("watch I 1 every -1", ["every must be from 0 to 3600 seconds"]),
    ],
)
def test_a_bad_watch_says_what_is_wrong_and_how_to_write_it(
    line: str, fragments: list[str]
) -> None:
    message = refused(line)
    for fragment in fragments:
        assert fragment in message, (line, message)


# ------------------------------------------------------------------ unwatch


@pytest.mark.parametrize("line", ["unwatch all", "unwatch ALL", "  unwatch   All  "])
def test_unwatch_all_names_no_variable(line: str) -> None:
    assert parsed(line, Unwatch).vars == ()


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ("unwatch P 10", ["P10"]),
        ("unwatch IO 1-3", ["IO1", "IO2", "IO3"]),
        ("unwatch P[0] J0", ["P0", "J0"]),
    ],
)
def test_unwatch_names_the_variables_typed(line: str, expected: list[str]) -> None:
    assert names(parsed(line, Unwatch).vars) == expected


@pytest.mark.parametrize(
    ("line", "fragments"),
    [
        ("unwatch", ["missing variable", "unwatch TYPE INDEX | all"]),
        ("unwatch I 1 junk", ["variables only", "'junk'", "unwatch TYPE INDEX | all"]),
        ("unwatch all I 1", ["unknown variable type 'all'"]),
    ],
)
def test_a_bad_unwatch_is_refused(line: str, fragments: list[str]) -> None:
    message = refused(line)
    for fragment in fragments:
        assert fragment in message, (line, message)


# ------------------------------------------------------------------ interval


@pytest.mark.parametrize(
    ("line", "seconds"),
    [
        ("interval 0.5", 0.5),
        ("interval 0", 0.0),
        ("interval 3600", 3600.0),
        ("interval 2e-3", 0.002),
    ],
)
def test_interval_takes_seconds(line: str, seconds: float) -> None:
    assert parsed(line, SetInterval).seconds == seconds


@pytest.mark.parametrize(
    ("line", "fragment"),
    [
        ("interval", "interval needs a number of seconds, e.g. interval 0.5"),
        ("interval abc", "interval needs a number of seconds, e.g. interval 0.5, got 'abc'"),
        ("interval -1", "interval must be from 0 to 3600 seconds"),
        ("interval 3600.1", "interval must be from 0 to 3600 seconds"),
        ("interval nan", "interval must be from 0 to 3600 seconds"),
        ("interval inf", "interval must be from 0 to 3600 seconds"),
    ],
)
def test_a_bad_interval_says_the_range(line: str, fragment: str) -> None:
    assert fragment in refused(line)


# ------------------------------------------------------------------ no-argument commands


@pytest.mark.parametrize("name", ["pause", "resume", "disconnect", "clear", "quit"])
def test_commands_without_arguments(name: str) -> None:
    assert parsed(name, Simple).step is Step(name)
    assert parsed(f"  {name.upper()}  ", Simple).step is Step(name)
    assert refused(f"{name} now") == f"{name} takes no argument"


# ------------------------------------------------------------------ connect


@pytest.mark.parametrize(
    ("line", "host", "port"),
    [
        ("connect 192.168.0.1", "192.168.0.1", 5006),
        ("connect rc8-cell3", "rc8-cell3", 5006),
        ("connect rc8:6000", "rc8", 6000),
        ("connect rc8:1", "rc8", 1),
        ("connect rc8:65535", "rc8", 65535),
        ("connect [::1]:5007", "::1", 5007),
        ("connect [fe80::1%eth0]:80", "fe80::1%eth0", 80),
        ("connect [::1]", "::1", 5006),
        ("connect ::1", "::1", 5006),  # a bare IPv6 address keeps the default port
    ],
)
def test_connect_takes_a_host_and_an_optional_port(line: str, host: str, port: int) -> None:
    command = parsed(line, Connect)
    assert (command.host, command.port) == (host, port)


@pytest.mark.parametrize(
    ("line", "fragment"),
    [
        ("connect", "connect needs one address: connect HOST or connect HOST:PORT"),
        ("connect a b", "connect needs one address: connect HOST or connect HOST:PORT"),
        ("connect :80", "connect needs a host: connect HOST or connect HOST:PORT"),
        ("connect []:80", "connect needs a host"),
        ("connect rc8:0", "port must be a number from 1 to 65535, got '0'"),
        ("connect rc8:65536", "port must be a number from 1 to 65535, got '65536'"),
        ("connect rc8:http", "port must be a number from 1 to 65535, got 'http'"),
        ("connect rc8:+80", "port must be a number from 1 to 65535, got '+80'"),
        ("connect rc8:", "port must be a number from 1 to 65535, got ''"),
        ("connect [::1]:x", "port must be a number from 1 to 65535, got 'x'"),
        ("connect [::1]:80x", "port must be a number from 1 to 65535, got '80x'"),
        ("connect rc8:\u0668\u0660", "port must be a number from 1 to 65535"),  # Arabic digits
    ],
)
def test_a_bad_address_is_refused(line: str, fragment: str) -> None:
    assert fragment in refused(line)


@pytest.mark.parametrize("line", ["connect [::1]x", "connect [::1"])
def test_a_bracketed_address_with_stray_text_is_refused(line: str) -> None:
    refused(line)


# ------------------------------------------------------------------ save and load


@pytest.mark.parametrize("action", ["save", "load"])
def test_save_and_load_take_the_rest_of_the_line_as_the_file(action: str) -> None:
    command = parsed(f"{action}   my cell 3.toml  ", WatchFile)
    assert command.action == action
    assert command.path == "my cell 3.toml"
    assert refused(action) == f"{action} needs a file name: {action} cell3.toml"


# ------------------------------------------------------------------ frames


@pytest.mark.parametrize(
    ("line", "on"), [("frames on", True), ("frames OFF", False), ("FRAMES On", True)]
)
def test_frames_on_and_off(line: str, on: bool) -> None:
    assert parsed(line, Frames).on is on


@pytest.mark.parametrize("line", ["frames", "frames maybe", "frames on off"])
def test_frames_needs_on_or_off(line: str) -> None:
    assert refused(line) == "frames needs on or off: frames on"


# ------------------------------------------------------------------ latency


@pytest.mark.parametrize(
    ("line", "count", "var"),
    [
        ("latency", 100, "I0"),
        ("latency 1000", 1000, "I0"),
        ("latency 1", 1, "I0"),
        ("latency 100000", 100000, "I0"),
        ("latency I 5", 100, "I5"),
        ("latency 50 P[3]", 50, "P3"),
        ("latency 7 io7", 7, "IO7"),
    ],
)
def test_latency_takes_a_count_and_a_variable(line: str, count: int, var: str) -> None:
    command = parsed(line, Latency)
    assert command.count == count
    assert str(command.var) == var


@pytest.mark.parametrize(
    ("line", "fragment"),
    [
        ("latency 0", "latency takes 1 to 100000 samples, got 0"),
        ("latency 100001", "latency takes 1 to 100000 samples, got 100001"),
        ("latency 5 I 1 2", "latency takes a count and a variable, not '2'"),
        ("latency 10 I", "latency [COUNT] [TYPE INDEX], e.g. latency 1000 I 0"),
        ("latency -5", "latency [COUNT] [TYPE INDEX], e.g. latency 1000 I 0"),
        ("latency 10 X 1", "unknown variable type 'X'"),
    ],
)
def test_a_bad_latency_is_refused(line: str, fragment: str) -> None:
    assert fragment in refused(line)


def test_latency_with_a_superscript_count_is_an_input_error() -> None:
    assert "latency" in refused("latency \u00b2")


# ------------------------------------------------------------------ help and unknown words


@pytest.mark.parametrize(
    ("line", "topic"),
    [
        ("help", None),
        ("HELP", None),
        ("help put", "put"),
        ("help  PUT ", "put"),
        ("help nope", "nope"),
    ],
)
def test_help_with_and_without_a_topic(line: str, topic: str | None) -> None:
    assert parsed(line, Help).topic == topic


@pytest.mark.parametrize("line", ["bogus", "gett I 1", "read I 1", "GETX:RC8:1:I:"])
def test_an_unknown_command_points_to_help_and_raw_lines(line: str) -> None:
    message = refused(line)
    assert f"unknown command {line.split()[0].lower()!r}" in message
    assert "type help for the list" in message
    assert "GET: or PUT:" in message


# ------------------------------------------------------------------ the helpers


def test_parse_var_returns_the_variable_and_what_follows() -> None:
    var, rest = parse_var("I 10 123", "usage")
    assert (var.kind.code, var.index, rest) == ("I", 10, " 123")
    var, rest = parse_var("p[3]x", "usage")
    assert (var.kind.code, var.index, rest) == ("P", 3, "x")
    var, rest = parse_var("  IO128", "usage")
    assert (var.kind.code, var.index, rest) == ("IO", 128, "")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "missing variable: get TYPE INDEX"),
        ("12", "missing variable: get TYPE INDEX"),
        ("I", "I needs an index: get TYPE INDEX"),
        ("I   ", "I needs an index: get TYPE INDEX"),
    ],
)
def test_parse_var_puts_the_usage_it_is_given_in_its_message(text: str, message: str) -> None:
    with pytest.raises(InputError) as info:
        parse_var(text, "get TYPE INDEX")
    assert str(info.value) == message


@pytest.mark.parametrize(
    ("line", "word", "rest"),
    [
        ("get I 1", "get", "I 1"),
        ("  GET   I 1  ", "get", "I 1"),
        ("quit", "quit", ""),
        ("   ", "", ""),
        ("", "", ""),
        ("send\tA  B", "send", "A  B"),
    ],
)
def test_split_word_gives_the_lower_cased_first_word_and_the_rest(
    line: str, word: str, rest: str
) -> None:
    assert split_word(line) == (word, rest)


@pytest.mark.parametrize(
    ("line", "raw"),
    [
        ("GET:RC8:1:I:", True),
        ("put:RC8:1:I:3,1", True),
        (" \tPUT:", True),
        ("GET:", True),
        ("get I 1", False),
        ("GETX:RC8", False),
        ("send GET:RC8:1:I:", False),
        ("GET", False),
        ("", False),
    ],
)
def test_is_raw_line(line: str, raw: bool) -> None:
    assert is_raw_line(line) is raw
