"""get, put, send (and raw GET:/PUT: lines), latency and wait: the commands that talk
to the controller, in the console, the REPL and (but latency) ``rac-console run``."""

from __future__ import annotations

from collections.abc import Sequence

from ....commands.conditions import parse_wait
from ....commands.exchange_parsers import parse_get, parse_put, parse_send
from ....commands.language import Exchange, Get, Latency, Put, Raw, Wait, parse_latency
from ....commands.outcome import Outcome
from ....commands.routing import Traits, WriteTrait
from ....protocol import KINDS
from ....session import ConnectFailed, Disconnected, TransportError
from ...published.events import Feedback, Measured, Message
from ..context import JobContext
from ..registry import (
    AT_A_TERMINAL,
    EVERYWHERE,
    CommandSpec,
    Option,
    Where,
    variable_completion,
)

NOT_CONNECTED = (
    "not connected: connect HOST[:PORT], connect PROFILE, or connect sim for the built-in simulator"
)
TYPE_NOTE = "TYPE: I F D S V P J T IO; I 10, I10 and I[10] name the same variable"


def run_exchange(context: JobContext, command: Exchange, line: str | None) -> list[Feedback]:
    """One exchange; a write crosses the job's gate (the target's rules: allow, confirm
    asked through the front end or refused with no one to ask, the value before and the
    read-back)."""
    controller = context.controller
    if controller is None:
        return [Message(NOT_CONNECTED, "error")]
    if isinstance(command, Get | Put):
        context.see((command.var,))
    outcome = controller.exchange(command, line)
    context.read_back(outcome)
    return [noted(context, outcome)]


def noted(context: JobContext, outcome: Outcome) -> Outcome:
    """A typed exchange that got no trustworthy reply is marked in the log (and one that
    found the controller unreachable is no early drop of a connection)."""
    if isinstance(outcome.failure, ConnectFailed):
        context.connect_failed(outcome.failure)
    if isinstance(outcome.failure, TransportError):
        context.mark_failure(outcome.failure)
    return outcome


def run_wait(context: JobContext, command: Wait, line: str | None) -> list[Feedback]:
    if command.after is not None:  # a cell runs it (engine/cell/cell.py): here is one target
        return [
            Message(
                f"after @{command.after.target} waits on another target: open a cell "
                "(-H cell3,cell4 or --cell NAME)",
                "error",
            )
        ]
    controller = context.controller
    if controller is None:
        return [Message(NOT_CONNECTED, "error")]
    context.see((command.var,))
    outcome = controller.wait(command, line, between=context.between)
    return [noted(context, outcome)]


def run_latency(context: JobContext, command: Latency, line: str | None) -> list[Feedback]:
    controller = context.controller
    if controller is None:
        return [Message(NOT_CONNECTED, "error")]
    try:
        summary = controller.latency(command.var, command.count, command.interval)
    except (ConnectFailed, Disconnected) as exc:
        context.connect_failed(exc if isinstance(exc, ConnectFailed) else None)
        return [Message(str(exc), "error")]
    return [Measured.of(f"GET {command.var}", summary)]


def _put_next(code: str, rest: list[str]) -> Sequence[Option]:
    if code == "IO" and not rest:
        return [("on", "set the bit (sends 11,-1)"), ("off", "clear it (sends 11,0)")]
    return ()


def _put_hint(args: list[str]) -> str:
    needs = ["TYPE", "INDEX", "VALUE..."]
    if args:
        kind = KINDS[args[0].upper()]
        needs = ["TYPE", "INDEX", *(["TEXT"] if kind.code == "S" else kind.value_hint.split())]
    return " ".join(needs[len(args) :])


def _wait_next(code: str, rest: list[str]) -> Sequence[Option]:
    if rest:
        return ()
    options = [("changes", "until the value differs from the first read")]
    if code == "IO":
        options[:0] = [("on", "until the bit is set"), ("off", "until it is clear")]
    options += [("==", "until it equals VALUE"), ("!=", "until it differs from VALUE")]
    if code in ("I", "F", "D"):
        options += [(op, f"until it is {op} NUMBER") for op in ("<", "<=", ">", ">=")]
    return options


_OPERATORS = ("==", "=", "!=", "<", "<=", ">", ">=")


def _wait_hint(args: list[str]) -> str:
    """What a ``wait`` still needs after its variable."""
    if len(args) < 2:
        return " ".join(["TYPE", "INDEX", "CONDITION", "[within", "SECONDS]"][len(args) :])
    words = [word.lower() for word in args[2:]]
    if not words:
        return "CONDITION [within SECONDS]"
    if words[-1] == "within":
        return "SECONDS"
    if "within" in words:
        return ""
    if words == [words[0]] and words[0] in _OPERATORS:
        return "VALUE [within SECONDS]"
    return "[within SECONDS]"


def _latency_hint(args: list[str]) -> str:
    """``latency [COUNT] [TYPE INDEX]``: a count is a number, so after one (or none) the
    variable follows."""
    if not args:
        return "[COUNT] [TYPE INDEX]"
    words = args
    if words[0].isascii() and words[0].isdigit():
        words = words[1:]
        if not words:
            return "[TYPE INDEX]"
    return {1: "INDEX"}.get(len(words), "")


SPECS = (
    CommandSpec(
        "get",
        "TYPE INDEX",
        "read a variable",
        parse_get,
        run_exchange,
        "get P 10",
        (TYPE_NOTE,),
        where=EVERYWHERE,
        takes_variable=True,
        complete=variable_completion(),
        types=(Get,),
    ),
    CommandSpec(
        "put",
        "TYPE INDEX VALUE...",
        "write a variable",
        parse_put,
        run_exchange,
        "put I 10 123",
        (TYPE_NOTE, "V/P/J/T take 3/7/8/10 numbers, IO takes on|off, S the rest of the line"),
        where=EVERYWHERE,
        takes_variable=True,
        complete=variable_completion(_put_next),
        hint=_put_hint,
        types=(Put,),
        traits=Traits(WriteTrait.ALWAYS),
    ),
    CommandSpec(
        "send",
        "TEXT",
        "send TEXT exactly as typed, even malformed",
        parse_send,
        run_exchange,
        "send GET:RC8:10:I:",
        where=EVERYWHERE,
        types=(Raw,),
        traits=Traits(WriteTrait.UNLESS_GET),
    ),
    CommandSpec(
        "latency",
        "[COUNT] [TYPE INDEX]",
        "measure round trips: COUNT GETs back to back (default 100 of I 0)",
        parse_latency,
        run_latency,
        "latency 1000",
        where=AT_A_TERMINAL | {Where.COMMAND_LINE},
        hint=_latency_hint,
        types=(Latency,),
    ),
    CommandSpec(
        "wait",
        "TYPE INDEX CONDITION [within SECONDS]",
        "read a variable until a condition holds (default: within 10 s)",
        parse_wait,
        run_wait,
        "wait IO 128 on within 2",
        (
            TYPE_NOTE,
            "CONDITION: on | off (IO), changes, or == != < <= > >= VALUE (< <= > >= for I F D)",
            "e.g. wait I 10 >= 100 within 30, wait P 0 changes within 5",
            "reads up to 100 times a second, watched rows still polled; "
            "not met in time: an error (exit 1 in run)",
        ),
        where=AT_A_TERMINAL | {Where.RUN},
        takes_variable=True,
        complete=variable_completion(_wait_next),
        hint=_wait_hint,
        types=(Wait,),
    ),
)
