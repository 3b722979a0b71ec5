"""``rac-console serve``: the console in a browser (the optional extra ``web``).

Its options (argparse only, so the grammar costs nothing at start) and its run: the
target options are checked here and passed to each session's console as they were
given; aiohttp and textual-serve are imported only when it runs, and their absence is
one line naming the extra, exit 2.
"""

from __future__ import annotations

import argparse
import sys

from ..engine.setup.poll_bounds import SERVED_MAX_ROWS, SERVED_MIN_INTERVAL
from ..present.served_bounds import DEFAULT_MEMORY_MIB, LEAST_MEMORY_MIB
from .options import port_number, seconds_of, whole_of

SERVE_HELP = "serve the console to a browser, behind a one-time link (pip install rac-console[web])"

SERVE_EPILOG = """\
Prints one link with a one-time token: open it in a browser, which gets a cookie for
the console (the token leaves the address bar). Listens on 127.0.0.1 unless --bind
names another address. Sessions are read-only unless --allow-writes, and then the
target's own confirm rules still apply. No TLS: on another machine, use it over the
cell's own network or an SSH tunnel:
  ssh -L 8006:127.0.0.1:8006 cell-pc    then open the link printed on cell-pc
The controller's port goes in -H (-H 192.168.0.1:5007) or before serve (-p 5007)."""

#: The extra and the modules it brings.
EXTRA_MODULES = ("aiohttp", "aiohttp_jinja2", "textual_serve")


def serve_options(sub: argparse.ArgumentParser) -> None:
    """``serve``'s options: the target's (as the console's, without -p: --port is the
    server's own) and the server's."""
    target = sub.add_argument_group("target (as the console's)")
    target.add_argument(
        "-H",
        "--host",
        default=argparse.SUPPRESS,
        help="controller address (HOST or HOST:PORT), or a target profile's name "
        "(default: the built-in simulator, one per session)",
    )
    target.add_argument(
        "--cell", metavar="NAME", default=argparse.SUPPRESS, help="a [cell.NAME] of the config file"
    )
    target.add_argument(
        "--timeout",
        type=seconds_of(allow_zero=False),
        default=argparse.SUPPRESS,
        metavar="SECONDS",
        help="per-request timeout (default 2)",
    )
    target.add_argument(
        "--no-verify",
        dest="verify",
        action="store_false",
        default=argparse.SUPPRESS,
        help="do not read a variable before and after a PUT",
    )
    target.add_argument(
        "--read-only",
        action="store_true",
        default=argparse.SUPPRESS,
        help="read-only sessions (the default without --allow-writes)",
    )
    server = sub.add_argument_group("server")
    server.add_argument(
        "--port",
        dest="serve_port",
        type=port_number,
        default=8006,
        metavar="N",
        help="port to listen on (default 8006; 0: any free one)",
    )
    server.add_argument(
        "--bind",
        dest="serve_bind",
        default="127.0.0.1",
        metavar="ADDR",
        help="address to listen on (default 127.0.0.1, this machine only)",
    )
    server.add_argument(
        "--allow-writes",
        action="store_true",
        help="let sessions write (the target's confirm rules still apply); default read-only",
    )
    server.add_argument(
        "--max-sessions",
        type=whole_of(""),
        default=1,
        metavar="N",
        help="consoles open at once (default 1); one more gets a page saying so",
    )
    server.add_argument(
        "--min-interval",
        type=seconds_of(allow_zero=True),
        default=SERVED_MIN_INTERVAL,
        metavar="SECONDS",
        help=f"least time between polls a session may ask for, interval or every "
        f"(default {SERVED_MIN_INTERVAL:g}; 0: back to back)",
    )
    server.add_argument(
        "--max-rows",
        type=whole_of(""),
        default=SERVED_MAX_ROWS,
        metavar="N",
        help=f"most rows a session may watch per target (default {SERVED_MAX_ROWS})",
    )
    server.add_argument(
        "--session-memory",
        type=memory_mib,
        default=DEFAULT_MEMORY_MIB,
        metavar="MIB",
        help=f"most memory each session's console may take, in MiB (default "
        f"{DEFAULT_MEMORY_MIB}; 0: no limit); at it the session ends and its page says why",
    )


def memory_mib(text: str) -> int:
    """``--session-memory``: 0 (no limit), or a whole number of MiB from
    :data:`LEAST_MEMORY_MIB` up (a console takes about 90 at start)."""
    if text.isascii() and text.isdigit() and (int(text) == 0 or int(text) >= LEAST_MEMORY_MIB):
        return int(text)
    raise argparse.ArgumentTypeError(
        f"give a number of MiB from {LEAST_MEMORY_MIB} up, or 0 for no limit, got {text!r}"
    )


def target_words(args: argparse.Namespace) -> list[str]:
    """The target options as given, one ``--name=value`` word each, for the sessions."""
    words = []
    if getattr(args, "host", None) is not None:
        words.append(f"--host={args.host}")
    if getattr(args, "port", None) is not None:
        words.append(f"--port={args.port}")
    if getattr(args, "cell", None) is not None:
        words.append(f"--cell={args.cell}")
    if getattr(args, "timeout", 2.0) != 2.0:
        words.append(f"--timeout={args.timeout}")
    if not getattr(args, "verify", True):
        words.append("--no-verify")
    return words


def _refusal(args: argparse.Namespace) -> str | None:
    if getattr(args, "yes", False):
        return "serve takes no --yes: a served console asks before every write to a confirm target"
    if getattr(args, "json", False):
        return "serve takes no --json: it serves the console, which prints no JSON"
    for option, name in (("record", "--record"), ("transcript", "--log")):
        if getattr(args, option, None) is not None:
            return f"serve takes no {name}: each session is a console of its own"
    if getattr(args, "read_only", False) and args.allow_writes:
        return "--read-only and --allow-writes say opposite things: give one"
    return None


def _target_settles(args: argparse.Namespace) -> bool:
    """The target resolves (a profile's name, a cell, the config file): said once here,
    not in every session; False after one line on stderr."""
    import copy

    from .cell import settle_cell
    from .target import settle_target

    checked = copy.copy(args)
    in_cell = settle_cell(checked)
    return in_cell is not False and (in_cell is True or settle_target(checked))


def _withheld() -> str | None:
    """Which settings of the config file the sessions do not read (they reach the
    network or the files), as each session says it; None: none."""
    from ..commands.config_keys import withheld_notice
    from ..engine.setup.config import load_config
    from ..engine.setup.where import Where

    return withheld_notice(load_config(where=Where.SERVED).withheld)


def missing_extra() -> str | None:
    """The module of the extra that cannot be imported, if one cannot."""
    import importlib

    for module in EXTRA_MODULES:
        try:
            importlib.import_module(module)
        except ImportError:
            return module
    return None


def serve_console(args: argparse.Namespace) -> int:
    if (why := _refusal(args)) is not None:
        print(f"rac-console: {why}", file=sys.stderr)
        return 2
    words = target_words(args)  # as given: each session resolves them itself
    if not _target_settles(args):
        return 2
    if (module := missing_extra()) is not None:
        print(
            f"rac-console: serve needs {module}, which the extra web brings: "
            'pip install "rac-console[web]"',
            file=sys.stderr,
        )
        return 2
    if (withheld := _withheld()) is not None:  # each session says it too, in its console
        print(f"rac-console: {withheld}", file=sys.stderr)
    import asyncio

    from ..serve.command import session_argv, session_environment
    from ..serve.server import ServeOptions, serve

    options = ServeOptions(
        argv=session_argv(words, args.allow_writes),
        environment=session_environment(args.min_interval, args.max_rows, args.session_memory),
        bind=args.serve_bind,
        port=args.serve_port,
        max_sessions=args.max_sessions,
        allow_writes=args.allow_writes,
    )
    return asyncio.run(serve(options))
