"""Every command of the language, declared once.

An entry holds the command's name, arguments, help, what completes after it, and
its parser. ``help``, completion, hints, the lexer's colours and
:func:`parse_command` all read this table; the engine runs the parsed command
objects with ``match``, and front ends act on :class:`~.language.Step` values.
Adding a command is one entry here, its parser, and its case in the engine.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

from ..protocol import InputError
from ..protocol.text import close_match
from .conditions import parse_log, parse_wait
from .language import (
    Command,
    Simple,
    Step,
    frame_file_parser,
    is_raw_line,
    parse_connect,
    parse_exchange,
    parse_frames,
    parse_get,
    parse_help,
    parse_interval,
    parse_latency,
    parse_load,
    parse_put,
    parse_save,
    parse_send,
    parse_unwatch,
    parse_watch,
    split_word,
)


class Completes(Enum):
    """What the word after the command name can be completed to."""

    NOTHING = "nothing"
    VARIABLE = "variable"  # TYPE, then an index seen before (then on|off for put IO)
    COMMAND = "command"  # help TOPIC
    ON_OFF = "on|off"
    TARGET = "target"  # connect: sim, then the config file's profiles


@dataclass(frozen=True)
class CommandSpec:
    name: str
    arguments: str
    summary: str
    parse: Callable[[str], Command]
    example: str = ""
    completes: Completes = Completes.NOTHING
    notes: tuple[str, ...] = ()  # more lines for ``help NAME``

    @property
    def usage(self) -> str:
        return f"{self.name} {self.arguments}".strip()

    @property
    def takes_variable(self) -> bool:
        return self.completes is Completes.VARIABLE


def _no_argument(step: Step) -> Callable[[str], Command]:
    def parse(rest: str) -> Command:
        if rest:
            raise InputError(f"{step.value} takes no argument")
        return Simple(step)

    return parse


_TYPE_NOTE = "TYPE: I F D S V P J T IO; I 10, I10 and I[10] name the same variable"

COMMANDS: dict[str, CommandSpec] = {
    spec.name: spec
    for spec in (
        CommandSpec(
            "get",
            "TYPE INDEX",
            "read a variable",
            parse_get,
            "get P 10",
            Completes.VARIABLE,
            (_TYPE_NOTE,),
        ),
        CommandSpec(
            "put",
            "TYPE INDEX VALUE...",
            "write a variable",
            parse_put,
            "put I 10 123",
            Completes.VARIABLE,
            (_TYPE_NOTE, "V/P/J/T take 3/7/8/10 numbers, IO takes on|off, S the rest of the line"),
        ),
        CommandSpec(
            "send",
            "TEXT",
            "send TEXT exactly as typed, even malformed",
            parse_send,
            "send GET:RC8:10:I:",
        ),
        CommandSpec(
            "watch",
            "TYPE INDEX [LABEL] [every SECONDS]",
            "add variables to the live table",
            parse_watch,
            "watch IO 128-135",
            Completes.VARIABLE,
            (_TYPE_NOTE,),
        ),
        CommandSpec(
            "unwatch",
            "TYPE INDEX | all",
            "remove variables from the live table",
            parse_unwatch,
            "unwatch P 10",
            Completes.VARIABLE,
            (_TYPE_NOTE,),
        ),
        CommandSpec(
            "interval", "SECONDS", "time between poll cycles", parse_interval, "interval 0.5"
        ),
        CommandSpec("pause", "", "stop polling the watched variables", _no_argument(Step.PAUSE)),
        CommandSpec("resume", "", "start polling again", _no_argument(Step.RESUME)),
        CommandSpec(
            "connect",
            "HOST[:PORT]",
            "talk to a controller (port 5006 by default), a profile, or sim",
            parse_connect,
            "connect 192.168.0.1",
            Completes.TARGET,
            notes=(
                "connect PROFILE: a [target.PROFILE] of the config file, with its label, "
                "colour and write rules (writes, allow), e.g. connect cell3",
                "connect sim: back to the built-in simulator (writes open)",
                "connect HOST[:PORT]: no profile; --read-only stays whatever the target",
            ),
        ),
        CommandSpec(
            "disconnect", "", "close the session and stop polling", _no_argument(Step.DISCONNECT)
        ),
        CommandSpec("save", "FILE", "save the watch list as TOML", parse_save, "save cell3.toml"),
        CommandSpec(
            "load", "FILE", "add the watch list saved in FILE", parse_load, "load cell3.toml"
        ),
        CommandSpec(
            "frames",
            "on|off",
            "echo every frame sent and received (REPL)",
            parse_frames,
            "frames on",
            Completes.ON_OFF,
        ),
        CommandSpec(
            "latency",
            "[COUNT] [TYPE INDEX]",
            "measure round trips: COUNT GETs back to back (default 100 of I 0)",
            parse_latency,
            "latency 1000",
        ),
        CommandSpec(
            "wait",
            "TYPE INDEX CONDITION [within SECONDS]",
            "read a variable until a condition holds (default: within 10 s)",
            parse_wait,
            "wait IO 128 on within 2",
            Completes.VARIABLE,
            (
                _TYPE_NOTE,
                "CONDITION: on | off (IO), changes, or == != < <= > >= VALUE (< <= > >= for I F D)",
                "e.g. wait I 10 >= 100 within 30, wait P 0 changes within 5",
                "reads up to 100 times a second, watched rows still polled; "
                "not met in time: an error (exit 1 in run)",
            ),
        ),
        CommandSpec(
            "log",
            "FILE.csv | stop",
            "log the watched values to a CSV file, one row per poll cycle",
            parse_log,
            "log cell3.csv",
            notes=(
                "columns: time, then one per field (P10.X, P10.Y, ..., IO128), "
                "taken when logging starts",
                "an existing file is appended to if its columns are the same; log alone "
                "says where the log goes",
            ),
        ),
        CommandSpec(
            "record",
            "FILE | stop",
            "append every frame to FILE as JSON lines from now on (as --record)",
            frame_file_parser("record"),
            "record cell3.jsonl",
            notes=(
                "record stop ends it; record alone says where frames go; "
                "rac-console sim --replay FILE serves what was recorded",
            ),
        ),
        CommandSpec(
            "transcript",
            "FILE | stop",
            "append every frame to FILE as a plain timestamped transcript (as --log)",
            frame_file_parser("transcript"),
            "transcript cell3.log",
            notes=("transcript stop ends it; transcript alone says where it goes",),
        ),
        CommandSpec("clear", "", "clear the frame log", _no_argument(Step.CLEAR)),
        CommandSpec(
            "help",
            "[COMMAND]",
            "list commands, or explain one",
            parse_help,
            "help put",
            Completes.COMMAND,
        ),
        CommandSpec("quit", "", "leave the console", _no_argument(Step.QUIT)),
    )
}

RAW_HELP = "GET:... / PUT:... lines are sent exactly as typed (raw RAC entry)"


def parse_command(line: str) -> Command | None:
    """One line of the command language; None for a blank line or a ``#`` comment."""
    stripped = line.strip()
    if not stripped or stripped.startswith("#"):
        return None
    if is_raw_line(line):
        return parse_exchange(line.rstrip("\r\n"))
    word, rest = split_word(line.rstrip("\r\n"))
    spec = COMMANDS.get(word)
    if spec is None:
        meant = close_match(word, COMMANDS)
        guess = f"did you mean {meant}? " if meant is not None else ""
        raise InputError(
            f"unknown command {word!r}: {guess}type help for the list, "
            "or start a raw line with GET: or PUT:"
        )
    return spec.parse(rest)


def help_lines(topic: str | None = None) -> list[str]:
    """The text of ``help`` or ``help COMMAND``."""
    if topic:
        spec = COMMANDS.get(topic.lower())
        if spec is None:
            return [f"no command {topic!r}: type help for the list"]
        lines = [f"{spec.usage}  -  {spec.summary}"]
        if spec.example:
            lines.append(f"  e.g. {spec.example}")
        lines.extend(f"  {note}" for note in spec.notes)
        return lines
    width = max(len(s.usage) for s in COMMANDS.values())
    return [f"{s.usage:<{width}}  {s.summary}" for s in COMMANDS.values()] + [RAW_HELP]
