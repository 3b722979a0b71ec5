"""Command-line entry point: the mode the words name, and its exit status.

Only argparse is imported at start; each mode imports its toolkit when it runs,
so ``--version``, ``get`` and ``sim`` start fast. The grammar is :mod:`.parser`.
"""

from __future__ import annotations

import argparse
import gc
import os
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from .parser import ONE_SHOT, POLLING_COMMANDS, CliParser, build_cli, build_parser

if TYPE_CHECKING:
    from ..engine.cell.cell import Cell

__all__ = ["CliParser", "build_cli", "build_parser", "main", "parse_args"]


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
    if getattr(args, "log_csv", None) is not None and args.command not in POLLING_COMMANDS:
        print(
            "rac-console: --log-csv logs watched values: use it with the console, "
            "the REPL, rac-console watch or the agent",
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
    if args.command == "serve":
        from .serve import serve_console

        return serve_console(args)
    if args.command != "sim":
        in_cell = settle_targets(args)
        if in_cell is False:
            return 2
        if args.command in POLLING_COMMANDS:
            from .plant import settle_plant

            if not settle_plant(args):
                return 2
        if in_cell and args.command in ("latency", "check"):
            from .cell import each_member

            if args.command == "latency":
                from .oneshot import latency as measure
            else:
                from .check import check as measure
            return each_member(args, measure)
    if args.command == "agent":
        from .agent import agent_command

        return agent_command(args)
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
        from .plant import say_plant_notices

        say_plant_notices(args)
        args.file = "-"  # no terminal: the REPL reads a script, like run -
        args.keep_going = True  # but as the REPL: a failed line stops nothing
        return run_script(args)
    if args.command == "sim":
        import asyncio

        from .simulator import serve

        use_uvloop()
        return asyncio.run(serve(args))
    return _interactive(args)


def settle_targets(args: argparse.Namespace) -> bool | None:
    """The targets the options name, resolved once for every mode (``args.target``, and
    ``args.cell_targets`` for several): True for a cell, None for one target, False
    after one line on stderr (a broken config, a name that is no target)."""
    from .cell import settle_cell
    from .target import settle_target

    in_cell = settle_cell(args)  # -H a,b or --cell NAME: several targets
    if in_cell is None and not settle_target(args):  # a broken config: one line, exit 2
        return False
    return in_cell


def make_cell(args: argparse.Namespace) -> Cell:
    """The console's or the REPL's cell of the settled targets (one target: a cell of
    one); InputError when a file named cannot be opened."""
    from ..engine import DEFAULT_INTERVAL, EngineOptions
    from ..engine.cell.cell import Cell, member_name
    from ..engine.setup.poll_bounds import bounds_for
    from ..engine.setup.where import Where
    from ..present.served import served

    # A console served to a browser runs only what reaches its targets and nothing
    # else of this machine (no file, no other host): the specs' Traits.reaches; and it
    # polls them within serve's bounds.
    where = Where.REPL if args.command is not None else Where.SERVED if served() else Where.CONSOLE
    options = EngineOptions(
        timeout=args.timeout,
        interval=DEFAULT_INTERVAL if args.interval is None else args.interval,
        verify=args.verify,
        cycles=args.command is None,  # the console draws trends; the REPL has none
        record=args.record,
        transcript=args.transcript,
        log_csv=getattr(args, "log_csv", None),
        bounds=bounds_for(where),
        **getattr(args, "plant", {}),
    )
    members = getattr(args, "cell_targets", None) or [(member_name(args.target), args.target)]
    from .agent import attach_for

    kind = "console" if args.command is None else "REPL"
    return Cell(members, options=options, where=where, attach=attach_for(args, kind, where))


def _after_first_paint() -> None:
    """The console painted its first screen: the collector runs again, and skips what
    the start made (it lives as long as the console)."""
    gc.freeze()
    gc.enable()


def _interactive(args: argparse.Namespace) -> int:
    """The full-screen console, or the REPL: one engine and history file for both."""
    from ..present.history import History, default_history_path
    from ..protocol.errors import InputError
    from ..protocol.text import terminal_safe

    try:
        cell = make_cell(args)
    except InputError as exc:
        print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
        return 2
    if args.command is None:  # the REPL had them on stderr; the console shows them here
        for member in cell.members:
            for notice in member.target.notices:
                member.engine.alert(notice)
        for notice in getattr(args, "plant_notices", ()):
            cell.members[0].engine.alert(notice)
    if args.watch:
        from ..engine.watch.watchlist import load

        try:
            load(args.watch)  # a broken list is one line now, not a console that starts half-set
        except InputError as exc:
            print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
            return 2
    from ..engine.setup.where import Where

    served = cell.where is Where.SERVED
    if not (sys.stdin.isatty() and sys.stdout.isatty()) and not served:
        print(
            "rac-console: the console needs a terminal; for scripts use "
            "'rac-console run -' (or get, put, send with --json)",
            file=sys.stderr,
        )
        return 2
    # Served to a browser: the lines typed there stay in that session's memory.
    history = History(None if served else args.history or default_history_path())
    if args.command == "repl":
        from ..commands.language import WatchFile
        from ..repl.repl import run_repl
        from .plant import say_plant_notices

        say_plant_notices(args)
        if args.watch:  # run first, its result printed as the REPL starts
            cell.submit_command(WatchFile("load", args.watch))
        watch_cell(cell, getattr(args, "cell_watch", ()))
        return run_repl(cell, history)
    from ..tui.app import run_console

    watch_cell(cell, getattr(args, "cell_watch", ()))
    profiles = () if served else sorted(args.target.profiles)  # a browser sees none
    return run_console(cell, history, args.watch, profiles, _after_first_paint)


def watch_cell(cell: Cell, lines: Sequence[str]) -> None:
    """A ``[cell.NAME]``'s watch list (``cell3 IO 128 part placed``), each on its target."""
    for line in lines:
        name, _, rest = line.partition(" ")
        cell.submit(f"@{name} watch {rest}")


def parse_args(words: Sequence[str]) -> argparse.Namespace:
    """The command line, with ``get``/``put``/``send`` words sorted by the pure splitter.

    argparse would take ``-1e3`` for an option, drop what the shell quoted once
    the words were joined, and cannot tell a trailing ``--json`` from a value; so
    for these commands argparse sees only the options, and ``args.words`` holds
    the other words as they came (``args.words_problem`` says why they cannot be
    used, if so). Other commands are argparse's alone.
    """
    if not words:  # the console, as most start it: no command word to know
        return build_cli(commands=False).parser.parse_args([])
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

    # The console's start makes hundreds of thousands of objects that live as long as it
    # does (modules, classes, the screen): the collector would walk them again and again
    # before its first paint. It is paused until then, and what the start made is frozen
    # (never walked again): see _after_first_paint. Every other mode has it at once.
    collecting = gc.isenabled()
    gc.disable()
    try:
        make_streams_safe()  # a Windows pipe (cp1252) must never fail after a PUT went out
        args = parse_args(sys.argv[1:] if argv is None else list(argv))
        if args.command is not None and collecting:
            gc.enable()
        return int(_dispatch(args))
    except KeyboardInterrupt:
        print("rac-console: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    finally:
        if collecting:
            gc.enable()
