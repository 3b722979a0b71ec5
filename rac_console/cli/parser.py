"""The command line's grammar: options, sub-commands and their help (argparse only,
so building it costs nothing at start)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from .. import __version__

if TYPE_CHECKING:
    pass


from .options import (
    DESCRIPTION,
    EPILOG,
    ONE_SHOT,
    WATCH_HELP,
    WORDS_EPILOG,
    CliParser,
    cell_size,
    count_of,
    global_options,
    help_option,
    plant_options,
    port_number,
    repeat_options,
    seconds_of,
    watch_options,
)
from .parse_errors import RacParser
from .serve import SERVE_EPILOG, SERVE_HELP, serve_options

__all__ = ["ONE_SHOT", "CliParser", "build_cli", "build_parser"]


CHECK_EPILOG = """\
Each step prints one line, ok or FAILED with the likely cause and what to check;
the check stops at the first that fails. Only GETs of I0 are sent.
  rac-console check -H 192.168.0.1
  rac-console check -H cell3 --json
Exit status: 0 all ok, 1 the controller answered the GET with an error,
3 a connection step failed."""

POLLING_COMMANDS = (None, "repl", "watch", "agent")
"""The commands that poll watched values (the console, the REPL, ``watch``, and the
agent's exporters): where ``--log-csv``, ``--mqtt`` and ``--metrics`` mean something."""


AGENT_HELP = (
    "hold one session to each target for every console, REPL, command and script of "
    "yours on this machine"
)
AGENT_EPILOG = """\
While it runs, a console, a REPL, a one-shot command, watch, run or a script for a
target it holds goes through it (the status line says "via agent"): one connection to
the controller, polled once for everyone, every write through its one gate in the
order received. --direct opens a session of its own.
  rac-console -H cell3 agent --watch plant.toml --mqtt mqtt://broker/cell3
feeds the plant the rows of plant.toml from the agent, whoever is attached (also
--metrics PORT, --log-csv FILE). See docs/agent.md.
"""


def build_parser() -> argparse.ArgumentParser:
    return build_cli().parser


def build_cli(commands: bool = True) -> CliParser:
    """The grammar; without ``commands``, only what comes before a command word (the
    console started with no words parses nothing more, and its start is timed)."""
    parser = RacParser(
        prog="rac-console",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        add_help=False,
    )
    top_actions = [
        help_option(parser),
        parser.add_argument("--version", action="version", version=f"rac-console {__version__}"),
        *global_options(parser, suppress=False),
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
            type=seconds_of(allow_zero=True),
            default=None,  # 0.5; before get, latency or watch: their own interval
            metavar="SECONDS",
            help="time between poll cycles (default 0.5); before get -r, latency or watch, "
            "their own interval",
        ),
        *plant_options(console, suppress=False),
    ]
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    if not commands:
        return CliParser(parser, tuple(top_actions), ())

    def command(
        name: str, help_text: str, usage: str | None = None, epilog: str | None = None
    ) -> tuple[argparse.ArgumentParser, list[argparse.Action]]:
        sub = subparsers.add_parser(
            name,
            help=help_text,
            description=help_text,
            usage=usage,
            epilog=epilog,
            formatter_class=argparse.RawDescriptionHelpFormatter,
            add_help=False,
        )
        return sub, [help_option(sub), *global_options(sub, suppress=True)]

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
    get_actions = repeat_options(get)
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
    run.add_argument(
        "--keep-going",
        action="store_true",
        help="run every line even after one failed (by default run stops at the first "
        "line that fails: refused, an error, an unknown outcome, a wait not met)",
    )
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
        "--count", type=count_of(int), default=None, metavar="N", help="how many GETs (default 100)"
    )
    latency.add_argument(
        "--interval",
        dest="latency_interval",
        type=seconds_of(allow_zero=True),
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
    subparsers.add_parser(
        "paths",
        help="where the config file and the history are on this machine",
        description="Where the config file and the history are on this machine.",
    )
    watch, _ = command("watch", WATCH_HELP, usage="%(prog)s [options] VAR...")
    watch_options(watch)
    plant_options(watch, suppress=True)
    repl, _ = command("repl", "a line-oriented console for plain terminals, ssh and serial")
    repl.add_argument(
        "--history",
        metavar="FILE",
        default=argparse.SUPPRESS,
        help="history file (shared with the full-screen console)",
    )
    repl.add_argument(
        "--interval",
        type=seconds_of(allow_zero=True),
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
    plant_options(repl, suppress=True)
    agent, _ = command("agent", AGENT_HELP, epilog=AGENT_EPILOG)
    agent.add_argument(
        "action",
        nargs="?",
        choices=("run", "status"),
        default="run",
        help="run (the default): hold the targets until Ctrl-C; status: what a running "
        "agent holds and who is attached",
    )
    agent.add_argument(
        "--watch",
        metavar="FILE",
        default=argparse.SUPPRESS,
        help="the TOML watch list the agent's own --mqtt, --metrics and --log-csv feed "
        "(a cell's watch lines too), whoever is attached",
    )
    agent.add_argument(
        "--log-csv",
        metavar="FILE",
        default=argparse.SUPPRESS,
        help="log the exported values to FILE, one CSV row per poll cycle",
    )
    plant_options(agent, suppress=True)
    serve = subparsers.add_parser(
        "serve",
        help=SERVE_HELP,
        description=SERVE_HELP,
        epilog=SERVE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    serve_options(serve)
    sim = subparsers.add_parser(
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
        type=port_number,
        default=5006,
        help="port to listen on (default 5006)",
    )
    sim.add_argument(
        "--idle-timeout",
        type=seconds_of(allow_zero=True),
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
    sim.add_argument(
        "--cell",
        dest="sim_cell",
        type=cell_size,
        default=None,
        metavar="N",
        help="serve N simulators (robotA, robotB, ...) on ports PORT, PORT+1, ... (--port 0: "
        "any free ones) playing a handshake: robotA's IO 128 (part placed) on every 4 s, "
        "robotB's IO 64 (go) answering it; Ctrl-C stops them all",
    )
    faults = sim.add_argument_group(
        "faults (each reproducible with --seed; change them while it runs with a line "
        "SIM:SET:delay_ms=50,drop_every=7 on any connection, read them with SIM:GET:)"
    )
    faults.add_argument(
        "--delay",
        dest="delay_ms",
        type=count_of(float),
        default=0,
        metavar="MS",
        help="delay every reply by MS milliseconds (up to 60000)",
    )
    faults.add_argument(
        "--jitter",
        dest="jitter_ms",
        type=count_of(float),
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
            type=count_of(int),
            default=0,
            metavar="N",
            help=text,
        )
    faults.add_argument(
        "--extra-gap",
        dest="extra_gap_ms",
        type=count_of(float),
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
        type=count_of(float),
        default=0,
        metavar="P",
        help="answer an error HRESULT from the spec's table with probability P (0 to 1)",
    )
    faults.add_argument(
        "--max-sessions",
        type=count_of(int),
        default=0,
        metavar="N",
        help="refuse connections beyond N at once",
    )
    faults.add_argument(
        "--seed",
        type=count_of(int),
        default=0,
        metavar="N",
        help="seed of the jitter and error choices (default 0)",
    )
    return CliParser(parser, tuple(top_actions), tuple(command_actions), get_actions)
