"""watch, unwatch, interval, pause, resume, save, load and log: the live table's
commands, at a terminal (the CLI's ``watch`` has its own words)."""

from __future__ import annotations

from collections.abc import Sequence

from ....commands.conditions import parse_log
from ....commands.language import (
    CsvLog,
    SetInterval,
    Simple,
    Step,
    Unwatch,
    VarRef,
    Watch,
    WatchFile,
    parse_interval,
    parse_load,
    parse_save,
    parse_unwatch,
    parse_watch,
)
from ....commands.routing import Reach, Traits
from ....protocol import InputError
from ....protocol.text import counted
from ...published.events import Feedback, Message
from ..context import CommandContext, CsvLogState
from ..registry import (
    AT_A_TERMINAL,
    EngineSpec,
    Option,
    Where,
    no_argument,
    variable_completion,
    words_of,
)
from .exchanges import TYPE_NOTE


def run_watch(context: CommandContext, command: Watch, line: str | None) -> list[Feedback]:
    variables = command.vars
    added = context.watch(variables, command.label, command.every)
    names = names_text(variables)
    text = f"watching {names}" if added else f"{names} already watched"
    if command.every is not None:
        text += f", polled every {command.every:g} s (other rows: interval {context.interval:g} s)"
    csv = context.csv_log()
    log = csv.log if not csv.cell else None  # a cell's log: its columns are the cell's
    if log is not None and not set(variables) <= set(log.variables):
        text += " (not in the CSV log's columns: log stop, then log FILE again to add them)"
    return [Message(text)]


def run_unwatch(context: CommandContext, command: Unwatch, line: str | None) -> list[Feedback]:
    variables = command.vars
    watched = {row.var for row in context.watched_rows()}
    absent = [v for v in variables if v not in watched]
    if variables and len(absent) == len(variables):
        return [Message(f"{names_text(variables)} not watched: nothing to stop", "error")]
    removed = context.unwatch(variables)
    text = f"stopped watching {counted(len(removed), 'variable')}"
    if absent:
        verb = "was" if len(absent) == 1 else "were"
        text += f" ({names_text(tuple(absent))} {verb} not watched)"
    return [Message(text)]


def run_interval(context: CommandContext, command: SetInterval, line: str | None) -> list[Feedback]:
    context.set_interval(command.seconds)
    return [Message(f"poll interval {command.seconds:g} s")]


def run_pause(context: CommandContext, command: Simple, line: str | None) -> list[Feedback]:
    paused = context.pause_polling(command.step is Step.PAUSE)
    return [Message("polling paused" if paused else "polling resumed")]


def run_watch_file(context: CommandContext, command: WatchFile, line: str | None) -> list[Feedback]:
    from ...watch import watchlist  # TOML: loaded by the console's save and load alone

    try:
        if command.action == "save":
            saved = [(row.var, row.label, row.every) for row in context.watched_rows()]
            watchlist.save(command.path, saved)
            return [Message(f"saved {len(saved)} watched variables to {command.path}")]
        rows = watchlist.load(command.path)
    except InputError as exc:
        return [Message(str(exc), "error")]
    for var, label, every in rows:
        context.watch((var,), label, every)
    return [Message(f"loaded {len(rows)} watched variables from {command.path}")]


def run_csv_log(context: CommandContext, command: CsvLog, line: str | None) -> list[Feedback]:
    return [_csv_log(context, command)]


def _csv_log(context: CommandContext, command: CsvLog) -> Message:
    state = context.csv_log()
    if command.stop:
        ended = context.stop_csv_log()
        if ended is not None:
            return Message(f"CSV log stopped: {counted(ended.rows, 'row')} in {ended.path}")
        if state.path is not None:
            return Message(f"CSV log to {state.path} stopped before its first row")
        return Message("no CSV log to stop", "error")
    if command.path is None:
        return _where_it_goes(state)
    if state.path is not None and not state.cell:  # a cell's log says so itself
        return Message(f"already logging to {state.path}: log stop first", "error")
    try:
        started = context.start_csv_log(command.path)
    except InputError as exc:
        return Message(f"CSV log not started: {exc}", "error")
    if state.cell:
        return Message(
            f"logging every target to {context.csv_log().path} from its next poll cycle: a "
            "column per target and variable watched then, a row per target's cycle (log "
            "stop ends it)"
        )
    if started is None:
        return Message(
            f"logging to {context.csv_log().path} from the first poll cycle: "
            "the variables watched then are its columns"
        )
    if started.failure is not None:  # its header failed: said here, not as an alert too
        return Message(started.failure, "error")
    how = "appending to" if started.appending else "logging to"
    return Message(
        f"{how} {started.path}: {counted(len(started.variables), 'variable')}, "
        "one row per poll cycle (log stop ends it)"
    )


def _where_it_goes(state: CsvLogState) -> Message:
    """``log`` alone: where the CSV log goes (in a cell: the cell's one log, for every
    target whichever asks)."""
    log = state.log
    if state.cell:
        if log is not None:
            rows = counted(log.rows, "row")
            return Message(f"logging every target to {log.path}: {rows} so far")
        if state.path is not None:
            waiting = ", ".join(state.waiting_for)
            return Message(
                f"logging to {state.path} once every target has polled (waiting for {waiting})"
            )
        return Message("not logging: log FILE.csv starts a CSV log of every target's values")
    if log is not None:
        count = counted(len(log.variables), "variable")
        return Message(f"logging {count} to {log.path}: {counted(log.rows, 'row')} so far")
    if state.path is not None:
        return Message(f"logging to {state.path} from the first poll cycle")
    return Message("not logging: log FILE.csv starts a CSV log of the watched values")


def names_text(variables: tuple[VarRef, ...]) -> str:
    """``IO4``, ``IO4..IO7 (4 variables)`` for a range, else ``P0, J0``."""
    if len(variables) == 1:
        return str(variables[0])
    first = variables[0]
    if all(v.kind == first.kind and v.index == first.index + n for n, v in enumerate(variables)):
        return f"{first}..{variables[-1]} ({len(variables)} variables)"
    if len(variables) <= 6:
        return ", ".join(str(v) for v in variables)
    return f"{', '.join(str(v) for v in variables[:5])} and {len(variables) - 5} more"


def _watch_hint(args: list[str]) -> str:
    if any(word.lower() == "every" for word in args[2:]):
        return "SECONDS" if args[-1].lower() == "every" else ""
    return words_of("TYPE INDEX [LABEL] [every SECONDS]")(args)


_ALL: Sequence[Option] = (("all", "every watched variable"),)

#: This module's commands (``help`` lists them in the order of the language's
#: COMMAND_WORDS).
SPECS = (
    EngineSpec(
        "watch",
        "TYPE INDEX [LABEL] [every SECONDS]",
        "add variables to the watch list, polled and shown live",
        parse_watch,
        run_watch,
        "watch IO 128-135",
        (TYPE_NOTE,),
        takes_variable=True,
        complete=variable_completion(),
        where=AT_A_TERMINAL | {Where.COMMAND_LINE},  # rac-console watch
        hint=_watch_hint,
        types=(Watch,),
    ),
    EngineSpec(
        "unwatch",
        "TYPE INDEX | all",
        "remove variables from the watch list",
        parse_unwatch,
        run_unwatch,
        "unwatch P 10",
        (TYPE_NOTE,),
        takes_variable=True,
        complete=variable_completion(first=_ALL),
        types=(Unwatch,),
    ),
    EngineSpec(
        "interval",
        "SECONDS",
        "time between poll cycles",
        parse_interval,
        run_interval,
        "interval 0.5",
        types=(SetInterval,),
    ),
    EngineSpec(
        "pause",
        "",
        "stop polling the watched variables",
        no_argument(Step.PAUSE),
        run_pause,
        where=AT_A_TERMINAL | {Where.COMMAND_LINE},  # watch --log-csv: until the log opened
        types=(Simple,),
    ),
    EngineSpec(
        "resume",
        "",
        "start polling again",
        no_argument(Step.RESUME),
        run_pause,
        where=AT_A_TERMINAL | {Where.COMMAND_LINE},
        types=(Simple,),
    ),
    EngineSpec(
        "save",
        "FILE",
        "save the watch list as TOML",
        parse_save,
        run_watch_file,
        "save cell3.toml",
        types=(WatchFile,),
        traits=Traits(reaches=Reach.FILES),
    ),
    EngineSpec(
        "load",
        "FILE",
        "add the watch list saved in FILE",
        parse_load,
        run_watch_file,
        "load cell3.toml",
        types=(WatchFile,),
        traits=Traits(reaches=Reach.FILES),
    ),
    EngineSpec(
        "log",
        "FILE.csv | stop",
        "log the watched values to a CSV file, one row per poll cycle",
        parse_log,
        run_csv_log,
        "log cell3.csv",
        notes=(
            "columns: time, then one per field (P10.X, P10.Y, ..., IO128), taken when "
            "logging starts",
            "an existing file is appended to if its columns are the same; log alone "
            "says where the log goes",
        ),
        where=AT_A_TERMINAL | {Where.COMMAND_LINE},  # rac-console watch --log-csv
        types=(CsvLog,),
        traits=Traits(reaches=Reach.FILES),
    ),
)
