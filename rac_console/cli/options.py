"""The command line's options and their value types, shared by the sub-commands
(argparse only)."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..commands.argv import Option


DESCRIPTION = "A console for DENSO RC8 controllers speaking RAC (TCP port 5006)."
EPILOG = """\
Without -H every command talks to a built-in RC8 simulator of its own, gone when
it ends (what put wrote too): rac-console sim serves one that stays, for
-H 127.0.0.1. -H NAME uses the [target.NAME] profile of config.toml in your
config directory (rac-console paths says where; RAC_CONSOLE_CONFIG names another
file): its address, label, colour and write rules.
Options may also come after the command, even after a value. A value that starts
with - and is not a number goes after --, where every word is the value:
  rac-console put S 10 -- -text
Exit status: 0 success, 1 the controller answered an error, 2 refused before
sending (bad input, read-only), 3 connection failure, timeout or bad reply,
4 a local file failed (--record on a full disk: said once, the work went on)."""


def seconds_of(allow_zero: bool) -> Callable[[str], float]:
    """An argparse type for a number of seconds up to an hour (0 allowed or not)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
        low = "0" if allow_zero else "more than 0"
        in_range = (value >= 0 if allow_zero else value > 0) and value <= 3600
        if not in_range:
            raise argparse.ArgumentTypeError(f"give {low} to 3600 seconds, got {text}")
        return value

    return parse


def count_of(kind: Callable[[str], float]) -> Callable[[str], float]:
    """An argparse type for a number that cannot be negative."""

    def parse(text: str) -> float:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if value < 0 or value != value:
            raise argparse.ArgumentTypeError(f"cannot be negative: {text}")
        return value

    return parse


def cell_size(text: str) -> int:
    """``sim --cell N``: how many simulators, one to a cell's most."""
    from ..commands.cells import MOST_TARGETS

    if not text.isdigit() or not 1 <= int(text) <= MOST_TARGETS:
        raise argparse.ArgumentTypeError(f"a cell has 1 to {MOST_TARGETS} simulators, got {text!r}")
    return int(text)


def port_number(text: str) -> int:
    if not text.isdigit() or not 0 <= int(text) <= 65535:
        raise argparse.ArgumentTypeError(f"a port is a number from 0 to 65535, got {text!r}")
    return int(text)


def help_option(parser: argparse.ArgumentParser) -> argparse.Action:
    """argparse's own -h/--help, added by hand so its Action can be listed."""
    return parser.add_argument(
        "-h", "--help", action="help", help="show this help message and exit"
    )


def global_options(parser: argparse.ArgumentParser, suppress: bool) -> list[argparse.Action]:
    """The options every command takes, before or after the command word."""

    def default(value: object) -> object:
        return argparse.SUPPRESS if suppress else value

    return [
        parser.add_argument(
            "-H",
            "--host",
            default=default(None),
            help="controller address, or the name of a target profile in the config file "
            "(default: the built-in simulator)",
        ),
        parser.add_argument(
            "--cell",
            metavar="NAME",
            default=default(None),
            help="open the targets of a [cell.NAME] of the config file together, one session "
            "each (--cell demo: simulators playing a handshake); -H cell3,cell4 opens a set "
            "by hand",
        ),
        parser.add_argument(
            "-p",
            "--port",
            type=port_number,
            default=default(None),  # None: 5006, or the profile's (an explicit -p wins)
            help="controller port (default 5006, or the profile's)",
        ),
        parser.add_argument(
            "--timeout",
            type=seconds_of(allow_zero=False),
            default=default(2.0),
            metavar="SECONDS",
            help="per-request timeout (default 2)",
        ),
        parser.add_argument(
            "--json",
            action="store_true",
            default=default(False),
            help="print one JSON object per result",
        ),
        parser.add_argument(
            "--read-only",
            action="store_true",
            default=default(False),
            help="send only well-formed GET requests; refuse everything else before sending",
        ),
        parser.add_argument(
            "--record",
            metavar="FILE",
            default=default(None),
            help="append every frame sent and received to FILE as JSON lines",
        ),
        parser.add_argument(
            "--log",
            metavar="FILE",
            dest="transcript",
            default=default(None),
            help="append every frame to FILE as a plain timestamped transcript, "
            "one line per frame (as tio's log)",
        ),
        parser.add_argument(
            "--no-verify",
            dest="verify",
            action="store_false",
            default=default(True),
            help="do not read a variable before and after a PUT (read-back is on by default)",
        ),
        parser.add_argument(
            "--yes",
            action="store_true",
            default=default(False),
            help='write to a target whose profile says writes = "confirm" without asking',
        ),
        parser.add_argument(
            "--direct",
            action="store_true",
            default=default(False),
            help="open a session of its own even when a running agent holds the target",
        ),
    ]


def plant_options(parser: argparse._ActionsContainer, suppress: bool) -> list[argparse.Action]:
    """``--mqtt``, ``--metrics`` and ``--opcua``: the console's, the REPL's, watch's and
    the agent's."""
    default = argparse.SUPPRESS if suppress else None
    return [
        parser.add_argument(
            "--mqtt",
            metavar="URL",
            default=default,
            help="publish the watched values to an MQTT broker: mqtt://HOST[:PORT]/PREFIX "
            "(or mqtts://), retained, one topic a variable",
        ),
        parser.add_argument(
            "--metrics",
            metavar="[HOST:]PORT",
            default=default,
            help="serve the watched values to Prometheus at http://HOST:PORT/metrics "
            "(127.0.0.1 unless another address is written out)",
        ),
        parser.add_argument(
            "--opcua",
            metavar="ENDPOINT",
            default=default,
            help="serve the watched values over OPC UA at opc.tcp://HOST:PORT "
            "(another address than loopback needs --opcua-security)",
        ),
        parser.add_argument(
            "--opcua-security",
            metavar="POLICY",
            choices=("none", "sign", "encrypt"),
            default=default,
            help="none (loopback only), sign or encrypt (Basic256Sha256; encrypt also signs)",
        ),
        parser.add_argument(
            "--opcua-writes",
            action="store_true",
            default=argparse.SUPPRESS if suppress else False,
            help="let OPC UA clients write the watched variables, through the same "
            "checks as a typed put (read-only, profiles, read-back)",
        ),
        parser.add_argument(
            "--opcua-user",
            metavar="NAME",
            default=default,
            help="OPC UA clients must log in as NAME, with the password in "
            "RAC_OPCUA_PASSWORD (needs --opcua-security)",
        ),
    ]


ONE_SHOT = ("get", "put", "send")
"""The commands whose words are sorted by :mod:`rac_console.commands.argv`, not argparse."""

WORDS_EPILOG = """\
Options may come anywhere, also after the value. Negative numbers are values
(put P 10 1 2 3 0 0 -90 -1); any other word that starts with - is refused, unless
it comes after --: every word after -- is taken as it is.
  rac-console put S 10 -- --not-an-option
  rac-console send -- -text"""


@dataclass(frozen=True)
class CliParser:
    """The argparse parser, and the options it knows for the word splitter.

    ``get``, ``put`` and ``send`` hand argparse only their options; their other
    words go to :func:`rac_console.commands.argv.split_words`, which needs to know
    every option spelling and whether it takes a value.
    """

    parser: argparse.ArgumentParser
    top_actions: tuple[argparse.Action, ...]  # options before the command word
    command_actions: tuple[argparse.Action, ...]  # options of get, put and send
    get_actions: tuple[argparse.Action, ...] = ()  # get's own: -r/--repeat, -i/--interval

    @property
    def top_options(self) -> dict[str, Option]:
        return option_table(self.top_actions)

    @property
    def command_options(self) -> dict[str, Option]:
        return option_table(self.command_actions)

    def options_for(self, command: str) -> dict[str, Option]:
        """The options of one of get, put and send (only get repeats)."""
        extra = self.get_actions if command == "get" else ()
        return option_table((*self.command_actions, *extra))


def option_table(actions: Iterable[argparse.Action]) -> dict[str, Option]:
    """Every spelling of every option, with its long name and the name of its value."""
    from ..commands.argv import Option

    table = {}
    for action in actions:
        names = action.option_strings
        long = next((name for name in names if name.startswith("--")), names[-1])
        metavar = None if action.nargs == 0 else str(action.metavar or action.dest.upper())
        table.update(dict.fromkeys(names, Option(long, metavar)))
    return table


def whole_of(hint: str) -> Callable[[str], int]:
    """An argparse type for a count of 1 or more; 0 is refused with ``hint``."""

    def parse(text: str) -> int:
        if not (text.isascii() and text.isdigit()) or int(text) < 1:
            why = hint if text.isascii() and text.isdigit() else ""
            raise argparse.ArgumentTypeError(f"give a whole number from 1 up, got {text!r}{why}")
        return int(text)

    return parse


def repeat_options(get: argparse.ArgumentParser) -> tuple[argparse.Action, ...]:
    """``get -r N -i S``: N reads, S seconds apart start to start (as redis-cli -r/-i).

    The interval defaults to 0, as in redis-cli and ``latency``: N reads now, back to
    back; a steady series over time is ``watch``. Both default to None so that ``-i``
    without ``-r`` can be refused rather than ignored."""
    return (
        get.add_argument(
            "-r",
            "--repeat",
            type=whole_of(" (-r 0 would read nothing or forever: for an endless series use watch)"),
            metavar="N",
            help="read N times, one result a line with its time (JSON: repetition, time)",
        ),
        get.add_argument(
            "-i",
            "--interval",
            dest="repeat_interval",
            type=seconds_of(allow_zero=True),
            metavar="S",
            help="with -r: S seconds from the start of one read to the next (default 0)",
        ),
    )


WATCH_HELP = "print watched variables as lines for pipes: watch IO 128-135 --every 0.2"


def watch_options(watch: argparse.ArgumentParser) -> None:
    watch.add_argument(
        "variables",
        metavar="VAR",
        nargs="+",
        help="as the console's watch: P 0, P[0], IO 128-135, several in a row",
    )
    watch.add_argument(
        "--every",
        "--interval",
        dest="every",
        type=seconds_of(allow_zero=True),
        default=None,  # 0.5
        metavar="S",
        help="seconds from the start of one cycle to the next (default 0.5, as the console)",
    )
    watch.add_argument(
        "--count",
        type=whole_of(" (leave --count out to watch until Ctrl-C)"),
        default=None,
        metavar="N",
        help="stop after N cycles (default: until Ctrl-C)",
    )
    watch.add_argument(
        "--log-csv",
        metavar="FILE",
        default=argparse.SUPPRESS,  # or the one given before the command
        help="also log each cycle to FILE as a CSV row, as the console's log FILE.csv",
    )
