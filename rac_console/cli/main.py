"""Command-line entry point: options, sub-commands and exit statuses.

Only argparse is imported at start; each mode imports its toolkit when it runs,
so ``--version``, ``get`` and ``sim`` start fast.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .. import __version__

if TYPE_CHECKING:
    from ..commands.argv import Option

DESCRIPTION = "A console for DENSO RC8 controllers speaking RAC (TCP port 5006)."
EPILOG = """\
Without -H every command talks to a built-in RC8 simulator. -H NAME uses the
[target.NAME] profile of config.toml in your config directory (rac-console paths
says where; RAC_CONSOLE_CONFIG names another file): its address, label, colour
and write rules.
Options may also come after the command, even after a value. A value that starts
with - and is not a number goes after --, where every word is the value:
  rac-console put S 10 -- -text
Exit status: 0 success, 1 the controller answered an error, 2 refused before
sending (bad input, read-only), 3 connection failure, timeout or bad reply,
4 a local file failed (--record on a full disk: said once, the work went on)."""


def _seconds(allow_zero: bool) -> Callable[[str], float]:
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


def _count(kind: Callable[[str], float]) -> Callable[[str], float]:
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


def _port(text: str) -> int:
    if not text.isdigit() or not 0 <= int(text) <= 65535:
        raise argparse.ArgumentTypeError(f"a port is a number from 0 to 65535, got {text!r}")
    return int(text)


def _help_option(parser: argparse.ArgumentParser) -> argparse.Action:
    """argparse's own -h/--help, added by hand so its Action can be listed."""
    return parser.add_argument(
        "-h", "--help", action="help", help="show this help message and exit"
    )


def _global_options(parser: argparse.ArgumentParser, suppress: bool) -> list[argparse.Action]:
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
            "-p",
            "--port",
            type=_port,
            default=default(None),  # None: 5006, or the profile's (an explicit -p wins)
            help="controller port (default 5006, or the profile's)",
        ),
        parser.add_argument(
            "--timeout",
            type=_seconds(allow_zero=False),
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
        return _option_table(self.top_actions)

    @property
    def command_options(self) -> dict[str, Option]:
        return _option_table(self.command_actions)

    def options_for(self, command: str) -> dict[str, Option]:
        """The options of one of get, put and send (only get repeats)."""
        extra = self.get_actions if command == "get" else ()
        return _option_table((*self.command_actions, *extra))


def _option_table(actions: Iterable[argparse.Action]) -> dict[str, Option]:
    """Every spelling of every option, with its long name and the name of its value."""
    from ..commands.argv import Option

    table = {}
    for action in actions:
        names = action.option_strings
        long = next((name for name in names if name.startswith("--")), names[-1])
        metavar = None if action.nargs == 0 else str(action.metavar or action.dest.upper())
        table.update(dict.fromkeys(names, Option(long, metavar)))
    return table


def _whole(hint: str) -> Callable[[str], int]:
    """An argparse type for a count of 1 or more; 0 is refused with ``hint``."""

    def parse(text: str) -> int:
        if not (text.isascii() and text.isdigit()) or int(text) < 1:
            why = hint if text.isascii() and text.isdigit() else ""
            raise argparse.ArgumentTypeError(f"give a whole number from 1 up, got {text!r}{why}")
        return int(text)

    return parse


def _repeat_options(get: argparse.ArgumentParser) -> tuple[argparse.Action, ...]:
    """``get -r N -i S``: N reads, S seconds apart start to start (as redis-cli -r/-i).

    The interval defaults to 0, as in redis-cli and ``latency``: N reads now, back to
    back; a steady series over time is ``watch``. Both default to None so that ``-i``
    without ``-r`` can be refused rather than ignored."""
    return (
        get.add_argument(
            "-r",
            "--repeat",
            type=_whole(" (-r 0 would read nothing or forever: for an endless series use watch)"),
            metavar="N",
            help="read N times, one result a line with its time (JSON: repetition, time)",
        ),
        get.add_argument(
            "-i",
            "--interval",
            dest="repeat_interval",
            type=_seconds(allow_zero=True),
            metavar="S",
            help="with -r: S seconds from the start of one read to the next (default 0)",
        ),
    )


WATCH_HELP = "print watched variables as lines for pipes: watch IO 128-135 --every 0.2"


def _watch_options(watch: argparse.ArgumentParser) -> None:
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
        type=_seconds(allow_zero=True),
        default=None,  # 0.5
        metavar="S",
        help="seconds from the start of one cycle to the next (default 0.5, as the console)",
    )
    watch.add_argument(
        "--count",
        type=_whole(" (leave --count out to watch until Ctrl-C)"),
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


CHECK_EPILOG = """\
Each step prints one line, ok or FAILED with the likely cause and what to check;
the check stops at the first that fails. Only GETs of I0 are sent.
  rac-console check -H 192.168.0.1
  rac-console check -H cell3 --json
Exit status: 0 all ok, 1 the controller answered the GET with an error,
3 a connection step failed."""

LOG_CSV_COMMANDS = (None, "repl", "watch")
"""Where ``--log-csv`` means something: the console, the REPL and ``watch``."""


def build_parser() -> argparse.ArgumentParser:
    return build_cli().parser


def build_cli() -> CliParser:
    parser = argparse.ArgumentParser(
        prog="rac-console",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        add_help=False,
    )
    top_actions = [
        _help_option(parser),
        parser.add_argument("--version", action="version", version=f"rac-console {__version__}"),
        *_global_options(parser, suppress=False),
    ]
    console = parser.add_argument_group("console options (no COMMAND: the full-screen console)")
    top_actions += [
        console.add_argument("--watch", metavar="FILE", help="load a TOML watch list at start"),
        console.add_argument(
            "--log-csv",
            metavar="FILE",
            help="log the watched values to FILE, one CSV row per poll cycle (also: log FILE)",
        ),
        console.add_argument(
            "--history", metavar="FILE", help="history file (default: in your state directory)"
        ),
        console.add_argument(
            "--interval",
            type=_seconds(allow_zero=True),
            default=None,  # 0.5; before get, latency or watch: their own interval
            metavar="SECONDS",
            help="time between poll cycles (default 0.5); before get -r, latency or watch, "
            "their own interval",
        ),
    ]
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

    def command(
        name: str, help_text: str, usage: str | None = None, epilog: str | None = None
    ) -> tuple[argparse.ArgumentParser, list[argparse.Action]]:
        sub = commands.add_parser(
            name,
            help=help_text,
            description=help_text,
            usage=usage,
            epilog=epilog,
            formatter_class=argparse.RawDescriptionHelpFormatter,
            add_help=False,
        )
        return sub, [_help_option(sub), *_global_options(sub, suppress=True)]

    # The positionals of get, put and send are for --help only: argparse never sees
    # those words (main() gives them to split_words), hence nargs "?" and "*".
    type_help = "I F D S V P J T IO; the index may be in the same word: P3, P[3]"
    get, command_actions = command(
        "get",
        "read a variable: get P 10 (also get P10, get 'P[10]')",
        usage="%(prog)s [options] TYPE INDEX",
        epilog=WORDS_EPILOG,
    )
    get.add_argument("type", metavar="TYPE", nargs="?", help=type_help)
    get.add_argument("index", metavar="INDEX", nargs="?", help="0 to 32767")
    get_actions = _repeat_options(get)
    put, _ = command(
        "put",
        "write a variable: put P 10 1 2 3 4 5 6 -1",
        usage="%(prog)s [options] TYPE INDEX VALUE...",
        epilog=WORDS_EPILOG,
    )
    put.add_argument("type", metavar="TYPE", nargs="?", help=type_help)
    put.add_argument("index", metavar="INDEX", nargs="?", help="0 to 32767")
    put.add_argument(
        "value",
        metavar="VALUE",
        nargs="*",
        help="the value; V/P/J/T take 3/7/8/10 numbers, IO on|off; S takes the words as "
        'given (several joined with one space; "" for an empty string)',
    )
    send, _ = command(
        "send",
        "send a raw RAC string as it is and print the reply",
        usage="%(prog)s [options] TEXT",
        epilog=WORDS_EPILOG,
    )
    send.add_argument("text", metavar="TEXT", nargs="?", help="e.g. 'GET:RC8:10:I:' (CR is added)")
    run, _ = command("run", "run console commands from FILE (or - for stdin) over one session")
    run.add_argument("file", metavar="FILE|-")
    latency, _ = command(
        "latency",
        "measure round trips of repeated GETs (like redis-cli --latency): "
        "latency [COUNT] [TYPE INDEX], as in the console",
        usage="%(prog)s [options] [COUNT] [TYPE INDEX]",
    )
    latency.add_argument(
        "words",
        metavar="COUNT TYPE INDEX",
        nargs="*",
        help="as the console's latency: latency 20 I 1 (or --count 20 --var 'I 1')",
    )
    latency.add_argument(
        "--count", type=_count(int), default=None, metavar="N", help="how many GETs (default 100)"
    )
    latency.add_argument(
        "--interval",
        dest="latency_interval",
        type=_seconds(allow_zero=True),
        default=None,  # 0
        metavar="S",
        help="pause between GETs (default 0)",
    )
    latency.add_argument(
        "--var", default=None, metavar="'TYPE INDEX'", help="the variable to read (default 'I 0')"
    )
    command(
        "check",
        "what stands between here and the controller: the name, the TCP connection, a GET, "
        "the round trip, a second session (GETs only; exit 3 at a connection failure)",
        epilog=CHECK_EPILOG,
    )
    commands.add_parser(
        "paths",
        help="where the config file and the history are on this machine",
        description="Where the config file and the history are on this machine.",
    )
    watch, _ = command("watch", WATCH_HELP, usage="%(prog)s [options] VAR...")
    _watch_options(watch)
    repl, _ = command("repl", "a line-oriented console for plain terminals, ssh and serial")
    repl.add_argument(
        "--history",
        metavar="FILE",
        default=argparse.SUPPRESS,
        help="history file (shared with the full-screen console)",
    )
    repl.add_argument(
        "--interval",
        type=_seconds(allow_zero=True),
        default=argparse.SUPPRESS,
        metavar="SECONDS",
        help="time between polls of watch (default 0.5)",
    )
    repl.add_argument(
        "--log-csv",
        metavar="FILE",
        default=argparse.SUPPRESS,
        help="log the watched values to FILE, one CSV row per poll cycle",
    )
    sim = commands.add_parser(
        "sim",
        help="run the RC8 simulator as a server",
        description="Serve the built-in RC8 simulator over TCP.",
    )
    sim.add_argument(
        "--bind",
        default="127.0.0.1",
        metavar="ADDR",
        help="address to listen on (default 127.0.0.1, loopback only)",
    )
    sim.add_argument(
        "--port",
        metavar="N",
        dest="sim_port",
        type=_port,
        default=5006,
        help="port to listen on (default 5006)",
    )
    sim.add_argument(
        "--idle-timeout",
        type=_seconds(allow_zero=True),
        default=0,
        metavar="SECONDS",
        help="close a connection that sends and reads nothing for SECONDS "
        "(up to 3600; default 0: never)",
    )
    sim.add_argument(
        "--no-control",
        action="store_true",
        help="turn off the SIM:SET:/SIM:GET: control lines (then answered "
        "E_INVALIDCOMMAND, like any unknown command)",
    )
    sim.add_argument(
        "--replay",
        metavar="FILE",
        default=None,
        help="serve what a controller answered in a --record FILE instead of simulated "
        "values: the Nth GET of a variable gets its Nth recorded answer (errors too); "
        "a variable never recorded answers E_NOTIMPL, a PUT E_ACCESSDENIED (read-only)",
    )
    sim.add_argument(
        "--replay-end",
        choices=("hold", "cycle"),
        default=None,
        help="after a variable's last recorded answer: hold it (the default: never shows "
        "a change that did not happen) or cycle back to its first",
    )
    faults = sim.add_argument_group(
        "faults (each reproducible with --seed; change them while it runs with a line "
        "SIM:SET:delay_ms=50,drop_every=7 on any connection, read them with SIM:GET:)"
    )
    faults.add_argument(
        "--delay",
        dest="delay_ms",
        type=_count(float),
        default=0,
        metavar="MS",
        help="delay every reply by MS milliseconds (up to 60000)",
    )
    faults.add_argument(
        "--jitter",
        dest="jitter_ms",
        type=_count(float),
        default=0,
        metavar="MS",
        help="vary each delay by up to ±MS milliseconds (up to 60000)",
    )
    for name, text in (
        ("slow", "answer every Nth reply 3 s late (past a 2 s client timeout)"),
        ("drop", "close the connection instead of every Nth reply"),
        ("stall", "never send every Nth reply"),
        ("garble", "send bytes that are not a RAC reply instead of every Nth"),
        ("extra", "send an unsolicited extra line after every Nth reply"),
    ):
        faults.add_argument(
            f"--{name}-every",
            dest=f"{name}_every",
            type=_count(int),
            default=0,
            metavar="N",
            help=text,
        )
    faults.add_argument(
        "--extra-gap",
        dest="extra_gap_ms",
        type=_count(float),
        default=None,
        metavar="MS",
        help="send that extra line as a write of its own, MS ms after the reply (0: straight "
        "after; up to 60000; without it, the line goes in the reply's own write)",
    )
    faults.add_argument(
        "--split", action="store_true", help="send replies in 2-byte pieces with pauses"
    )
    faults.add_argument(
        "--error-rate",
        type=_count(float),
        default=0,
        metavar="P",
        help="answer an error HRESULT from the spec's table with probability P (0 to 1)",
    )
    faults.add_argument(
        "--max-sessions",
        type=_count(int),
        default=0,
        metavar="N",
        help="refuse connections beyond N at once",
    )
    faults.add_argument(
        "--seed",
        type=_count(int),
        default=0,
        metavar="N",
        help="seed of the jitter and error choices (default 0)",
    )
    return CliParser(parser, tuple(top_actions), tuple(command_actions), get_actions)


def use_uvloop() -> bool:
    """Run on uvloop when the optional extra is installed (``pip install .[fast]``);
    RAC_CONSOLE_NO_UVLOOP=1 turns it off."""
    if os.environ.get("RAC_CONSOLE_NO_UVLOOP"):
        return False
    try:
        import uvloop  # type: ignore[import-not-found, unused-ignore]
    except ImportError:
        return False
    import asyncio

    asyncio.set_event_loop_policy(uvloop.EventLoopPolicy())
    return True


def _dispatch(args: argparse.Namespace) -> int:
    if getattr(args, "port", None) not in (None, 5006) and not getattr(args, "host", None):
        print(
            f"rac-console: -p {args.port} needs -H HOST: without -H every command talks "
            "to a built-in simulator of its own",
            file=sys.stderr,
        )
        return 2
    if getattr(args, "log_csv", None) is not None and args.command not in LOG_CSV_COMMANDS:
        print(
            "rac-console: --log-csv logs watched values: use it with the console, "
            "the REPL or rac-console watch",
            file=sys.stderr,
        )
        return 2
    from .option_scope import refusal

    if (why := refusal(args)) is not None:  # an option given where it means nothing
        print(f"rac-console: {why}", file=sys.stderr)
        return 2
    if args.command == "paths":
        from .paths import paths

        return paths()
    if args.command != "sim":
        from .target import settle_target

        if not settle_target(args):  # a broken config file: one line, exit 2
            return 2
    if args.command == "get" and (args.repeat, args.repeat_interval) != (None, None):
        from .live import repeat_get

        return repeat_get(args)
    if args.command == "watch":
        from .live import watch

        return watch(args)
    if args.command in ("get", "put", "send"):
        from .oneshot import one_command

        return one_command(args)
    if args.command == "latency":
        from .oneshot import latency

        return latency(args)
    if args.command == "check":
        from .check import check

        return check(args)
    if args.command == "run":
        from .oneshot import run_script

        return run_script(args)
    if args.command == "repl" and not sys.stdin.isatty():
        from .oneshot import run_script

        args.file = "-"  # no terminal: the REPL reads a script, like run -
        return run_script(args)
    if args.command == "sim":
        import asyncio

        from .simulator import serve

        use_uvloop()
        return asyncio.run(serve(args))
    return _interactive(args)


def _interactive(args: argparse.Namespace) -> int:
    """The full-screen console, or the REPL: one engine and history file for both."""
    from ..engine import DEFAULT_INTERVAL, Engine, EngineOptions
    from ..engine.registry import Where
    from ..present.history import History, default_history_path
    from ..protocol import InputError
    from ..protocol.text import terminal_safe

    options = EngineOptions(
        timeout=args.timeout,
        interval=DEFAULT_INTERVAL if args.interval is None else args.interval,
        verify=args.verify,
        cycles=args.command is None,  # the console draws trends; the REPL has none
        record=args.record,
        transcript=args.transcript,
        log_csv=getattr(args, "log_csv", None),
    )
    where = Where.CONSOLE if args.command is None else Where.REPL
    try:
        engine = Engine(target=args.target, options=options, where=where)
    except InputError as exc:
        print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
        return 2
    if args.command is None:  # the REPL had them on stderr; the console shows them here
        for notice in args.target.notices:
            engine.alert(notice)
    if args.watch:
        from ..engine.watchlist import load

        try:
            load(args.watch)  # a broken list is one line now, not a console that starts half-set
        except InputError as exc:
            print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
            return 2
    if not (sys.stdin.isatty() and sys.stdout.isatty()):
        print(
            "rac-console: the console needs a terminal; for scripts use "
            "'rac-console run -' (or get, put, send with --json)",
            file=sys.stderr,
        )
        return 2
    history = History(args.history or default_history_path())
    if args.command == "repl":
        from ..commands.language import WatchFile
        from ..repl.repl import run_repl

        if args.watch:  # run first, its result printed as the REPL starts
            engine.submit_command(WatchFile("load", args.watch))
        return run_repl(engine, history)
    from ..tui.app import run_console

    return run_console(engine, history, args.watch, sorted(args.target.profiles))


def parse_args(words: Sequence[str]) -> argparse.Namespace:
    """The command line, with ``get``/``put``/``send`` words sorted by the pure splitter.

    argparse would take ``-1e3`` for an option, drop what the shell quoted once
    the words were joined, and cannot tell a trailing ``--json`` from a value; so
    for these commands argparse sees only the options, and ``args.words`` holds
    the other words as they came (``args.words_problem`` says why they cannot be
    used, if so). Other commands are argparse's alone.
    """
    cli = build_cli()
    if not set(ONE_SHOT) & set(words):  # --version and the console skip the import
        return cli.parser.parse_args(words)
    from ..commands.argv import find_command, split_words

    at = find_command(words, cli.top_options)
    if at is None or words[at] not in ONE_SHOT:
        args = cli.parser.parse_args(words)
        if args.command in ONE_SHOT:  # behind a leading --, where argparse read the words
            positionals = [args.type, args.index] if args.command != "send" else [args.text]
            args.words = [w for w in positionals if w is not None] + getattr(args, "value", [])
            args.words_problem = None
        return args
    options = cli.options_for(words[at])
    split = split_words(words[at], words[at + 1 :], options, before=words[:at])
    args = cli.parser.parse_args([*words[: at + 1], *split.options])
    args.words = list(split.operands)
    args.words_problem = split.problem
    return args


def main(argv: Sequence[str] | None = None) -> int:
    from ..present.glyphs import make_streams_safe

    make_streams_safe()  # a Windows pipe (cp1252) must never fail after a PUT went out
    args = parse_args(sys.argv[1:] if argv is None else list(argv))
    try:
        return int(_dispatch(args))
    except KeyboardInterrupt:
        print("rac-console: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
