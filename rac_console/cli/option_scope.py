"""Which commands take which option: an option given where it means nothing is refused
(exit 2, one line naming the commands that take it), never silently ignored; one given
before the command word does what it says for that command, as after it.
"""

from __future__ import annotations

import argparse
import sys

from ..present.served import served
from .parser import POLLING_COMMANDS

#: Interval words: the top-level --interval, taken over by each command's own option.
_INTERVAL_OF = {"get": "repeat_interval", "latency": "latency_interval", "watch": "every"}


def _name(command: str | None) -> str:
    return "the console" if command is None else command


def refusal(args: argparse.Namespace) -> str | None:
    """Why an option given cannot be used with ``args.command``; None when every option
    given means something there. Moves a top-level ``--interval`` to the command's own."""
    command: str | None = args.command
    if command in ("sim", "paths"):
        return _before_own(args, command)
    if getattr(args, "watch", None) is not None and command not in (None, "repl", "agent"):
        return (
            f"--watch loads a watch list at start: the console, the REPL and the agent take "
            f"it, not {_name(command)} (rac-console watch takes variables: watch I 0-7)"
        )
    if getattr(args, "history", None) is not None and command not in (None, "repl"):
        return (
            f"--history names the console's and the REPL's history file: "
            f"{_name(command)} keeps no history"
        )
    for option in ("mqtt", "metrics", "opcua"):
        if getattr(args, option, None) is not None and command not in POLLING_COMMANDS:
            return (
                f"--{option} feeds the plant the watched values: the console, the REPL, "
                f"watch and the agent take it, not {_name(command)}"
            )
    interval = getattr(args, "interval", None)
    if interval is not None and command not in (None, "repl"):
        own = _INTERVAL_OF.get(command) if command is not None else None
        if own is None:
            return (
                f"--interval is the time between polls or reads: the console, the REPL, "
                f"watch, get -r and latency take it, not {_name(command)}"
            )
        if getattr(args, own, None) is not None:
            return f"the interval is given twice (--interval before {command}, and after it)"
        setattr(args, own, interval)
    # else: "needs a terminal" (a console served to a browser is as one at a terminal)
    interactive = (sys.stdin.isatty() and sys.stdout.isatty()) or served()
    if args.json and command in (None, "repl") and interactive:
        return (
            "--json prints results for scripts: get, put, send, run, watch, latency and "
            f"check take it (or rac-console repl fed from a pipe), not {_name(command)}"
        )
    if args.yes and command in (None, "repl") and interactive:
        return (
            "--yes says yes ahead for scripts (put, send and run); the console and the REPL "
            "ask before every write to a confirm target"
        )
    # --yes and --no-verify on a command that writes nothing change nothing, as they say:
    # kept, so an alias of global options (rac='rac-console -H cell3 --yes') works for all.
    return None


#: The top-level options and their defaults: any other value before ``sim`` was given.
_TOP_DEFAULTS = {
    "host": None,
    "cell": None,
    "port": None,
    "timeout": 2.0,
    "json": False,
    "read_only": False,
    "record": None,
    "transcript": None,
    "verify": True,
    "yes": False,
    "watch": None,
    "log_csv": None,
    "history": None,
    "interval": None,
    "mqtt": None,
    "metrics": None,
    "opcua": None,
    "opcua_security": None,
    "opcua_writes": False,
    "opcua_user": None,
}


def _before_own(args: argparse.Namespace, command: str) -> str | None:
    given = [
        name for name, default in _TOP_DEFAULTS.items() if getattr(args, name, default) != default
    ]
    if not given:
        return None
    shown = ", ".join("--" + name.replace("_", "-") for name in given)
    return (
        f"{command} takes its own options ({shown} given before it): "
        f"see rac-console {command} --help"
    )
