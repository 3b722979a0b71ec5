"""Live values for pipes: ``get ... -r N -i S`` and ``watch VAR...``, one line at a time.

Both are the console's ``watch`` run by an engine (:mod:`rac_console.engine`): its
poller reads the variables on its schedule, its CSV log writes ``--log-csv``, and each
poll cycle comes back as a :class:`~rac_console.engine.Cycle` that becomes a line. Every
line is flushed as it is written, so ``| grep --line-buffered`` sees it at once; a
reader that goes away (``| head -3``) ends the command quietly. The exit status is the
worst seen, as for ``run``, and only it is kept (days of watching hold no more memory).
"""

from __future__ import annotations

import argparse
import json
import threading
from collections.abc import Callable, Mapping
from typing import Any

from ..commands.argv import exchange_from_words, input_line
from ..commands.language import (
    Command,
    CsvLog,
    Get,
    Simple,
    Step,
    VarRef,
    Watch,
    parse_var_list,
)
from ..commands.outcome import ExitStatus, Outcome, refused, worst
from ..commands.target import Target
from ..engine import (
    SIMULATOR_NOTICE,
    Alert,
    Batch,
    Cycle,
    EngineLike,
    EngineOptions,
    Message,
    Result,
    Status,
)
from ..engine.cell.cell import Cell, member_name
from ..engine.exchange.execute import outcome_of
from ..engine.setup.where import Where
from ..engine.watch.csvlog import timestamp
from ..present.batches import BatchReader
from ..present.render import error_text, outcome_text, print_error
from ..protocol import InputError, hresult_name
from ..session import BadReply, ConnectFailed, RequestTimeout
from .agent import attach_for
from .cell import pick_member, words_by_member
from .oneshot import Output, pointed_to_check
from .pipes import reader_gone, stderr_may_close, write_line

WATCH_USAGE = "rac-console watch TYPE INDEX [TYPE INDEX|TYPE FIRST-LAST]..., e.g. watch IO 128-135"

#: watch's default cycle, as the console's poll interval.
WATCH_EVERY = 0.5
#: How long the CLI waits for the engine at a time (Ctrl-C is seen between waits).
WAKE_EVERY = 0.5


# ------------------------------------------------------------ the shared run

#: What a cycle read: each variable's outcome, None when it was not read (the
#: connection failed earlier in that cycle).
Results = dict[VarRef, Outcome | None]
#: Shows one cycle of a target (its name when a cell is open, else None; the cycle's
#: number from 1; its wall-clock time; its results).
Show = Callable[[str | None, int, float, Results], None]


def run_live(
    args: argparse.Namespace,
    output: Output,
    variables: tuple[VarRef, ...],
    show: Show,
    *,
    count: int | None,
    interval: float,
    until_ctrl_c: bool,
    line: str | None = None,
    log_csv: str | None = None,
    by_member: Mapping[str, tuple[VarRef, ...]] | None = None,
) -> ExitStatus:
    """``count`` cycles (None: without end) of ``variables``, ``interval`` apart, by an
    engine's poller; each shown as it ends. In a cell, ``by_member`` adds each target's
    own (``watch @robotA IO 128``); a target with none is not polled.

    The status is the worst one seen. A closed stdout ends it quietly; Ctrl-C ends it
    the same way when ``until_ctrl_c`` (the usual end of a watch), else it goes on up
    to ``main`` (status 130: fewer results than asked for).
    """
    woke = threading.Event()
    members = getattr(args, "cell_targets", None) or [(member_name(args.target), args.target)]
    options = EngineOptions(
        timeout=args.timeout,
        interval=interval,
        cycles=True,
        record=args.record,
        transcript=getattr(args, "transcript", None),
        frames=False,
        cut_cycles=True,
        max_cycles=count,
        readings=True,
        **getattr(args, "plant", {}),
    )
    try:
        cell = Cell(
            members, options=options, notify=woke.set, where=Where.COMMAND_LINE,
            attach=attach_for(args, "watch", Where.COMMAND_LINE),
        )  # fmt: skip
    except InputError as exc:  # --record cannot open its file
        print_error(output.err, str(exc))
        return ExitStatus.REFUSED
    own = by_member or {}
    cell_alerts = _Alerts(output)
    runs = [
        _LiveRun(m.engine, None if cell.single else m.name, output, watched, show, line)
        for m in cell.members
        if (watched := tuple(dict.fromkeys((*variables, *own.get(m.name, ()))))) or not own
    ]
    cell.start(connect=False)

    def wait() -> None:
        woke.wait(WAKE_EVERY)
        woke.clear()
        cell_alerts.read(None, cell.outbox.drain())  # a file of the cell's that failed
        for run in runs:
            run.take(run.engine.outbox.drain())

    try:
        for n, run in enumerate(runs):  # a cell's CSV log is one, started at one target
            run.submit_set_up(log_csv if n == 0 else None)
        while not all(run.set_up_done() for run in runs):
            wait()
        if not all(run.set_up_ok() for run in runs):
            cell.stop()
            return ExitStatus.REFUSED
        for run in runs:
            run.engine.submit_command(Simple(Step.RESUME))
        while count is None or any(run.shown < count for run in runs):
            wait()
    except KeyboardInterrupt:
        if not until_ctrl_c:
            raise
    except OSError as exc:
        if not reader_gone(exc):
            raise
    finally:
        cell.stop()
    cell_alerts.read(None, cell.outbox.drain())
    for run in runs:
        run.ended = True
        run.take(run.engine.outbox.drain())  # the last alerts (a file that failed at the end)
    return output.status(worst([run.worst for run in runs]))


class _Alerts(BatchReader):
    """The cell's own batch: only the alerts of its files are said."""

    def __init__(self, output: Output) -> None:
        self.output = output

    def take_alert(self, target: str | None, alert: Alert) -> None:
        self.output.alert(alert)


class _LiveRun(BatchReader):
    """The CLI's side of one target's engine: what it said, and the worst status seen."""

    def __init__(
        self,
        engine: EngineLike,
        name: str | None,
        output: Output,
        variables: tuple[VarRef, ...],
        show: Show,
        line: str | None,
    ) -> None:
        self.engine, self.name, self.output = engine, name, output
        self.variables, self.show, self.line = variables, show, line
        self.worst = ExitStatus.OK
        self.shown = 0  # cycles shown
        self._results: list[Result] = []
        self._set_up_steps = 0
        self._told_simulator = False
        self.ended = False  # stopped: a cycle the stop cut short is no result
        self.csv_failure: str | None = None  # why the CSV log failed once it was open

    def submit_set_up(self, log_csv: str | None) -> None:
        """The variables watched (and the CSV log started), as the console would, with
        polling paused until the log is known good: a refused log sends nothing."""
        commands: list[Command] = [Simple(Step.PAUSE), Watch(self.variables)]
        if log_csv is not None:
            commands.append(CsvLog(log_csv))
        for command in commands:
            self.engine.submit_command(command)
        self._set_up_steps = len(commands)

    def set_up_done(self) -> bool:
        return len(self._results) >= self._set_up_steps

    def set_up_ok(self) -> bool:
        """False when the set-up was refused (said on stderr; nothing was sent)."""
        engine = self.engine
        for result in self._results:
            errors = [
                f.text for f in result.feedback if isinstance(f, Message) and f.level == "error"
            ]
            if errors and self.csv_failure is not None:  # opened, then failed: go on (exit 4)
                for error in errors:
                    self.output.local_failure(error)
            elif errors:
                engine.stop()
                for error in errors:
                    print_error(self.output.err, error)
                return False
        return True

    def take(self, batch: Batch) -> None:
        self.read(self.name or "", batch)

    def take_status(self, target: str, status: Status) -> None:
        self.csv_failure = status.csv_failure
        if status.is_simulator and not self._told_simulator:
            self._told_simulator = True
            print_error(self.output.err, f"{SIMULATOR_NOTICE} (at {status.host}:{status.port})")

    def take_alert(self, target: str | None, alert: Alert) -> None:
        self.output.alert(alert)  # a --record, --log or CSV file that failed

    def take_result(self, target: str | None, result: Result) -> None:
        self._results.append(result)

    def take_cycle(self, target: str | None, cycle: Cycle) -> None:
        if not self.ended:
            self._cycle(cycle)

    def _cycle(self, cycle: Cycle) -> None:
        read = {var: outcome_of(Get(var), reading, self.line) for var, reading in cycle.readings}
        results: Results = {var: read.get(var) for var in self.variables}
        # Added to the worst before the line is printed: a Ctrl-C during the print must
        # not lose them.
        statuses = [o.status for o in results.values() if o is not None]
        self.worst = worst([self.worst, *statuses])
        self.shown += 1
        self.show(self.name, self.shown, cycle.time, results)


# ------------------------------------------------------------------ get -r N


@stderr_may_close()
def repeat_get(args: argparse.Namespace) -> ExitStatus:
    """``get TYPE INDEX -r N [-i S]``: N results, one a line, each with its time."""
    output = Output(args.json)
    line = input_line("get", args.words)
    try:
        if args.words_problem is not None:
            raise InputError(args.words_problem)
        target = pick_member(args)  # a cell: get @cell3 I 10 -r 5
        if args.repeat is None:
            raise InputError(
                "-i needs -r N, how many times to read: "
                f"rac-console get {' '.join(args.words) or 'I 0'} -r 10 -i {args.repeat_interval:g}"
            )
        command = exchange_from_words("get", args.words)
    except InputError as exc:
        output.show(refused(line, str(exc)))
        return ExitStatus.REFUSED
    assert isinstance(command, Get)  # get's words make a Get
    output.target = target

    def repetition(_: str | None, number: int, wall: float, results: Results) -> None:
        outcome = results[command.var]
        if outcome is not None:
            _show_repetition(output, outcome, number, timestamp(wall))

    interval = args.repeat_interval or 0.0
    return run_live(
        args,
        output,
        (command.var,),
        repetition,
        count=args.repeat,
        interval=interval,
        until_ctrl_c=False,
        line=line,
    )


def _show_repetition(output: Output, outcome: Outcome, number: int, started: str) -> None:
    """JSON with ``repetition`` and ``time``; text as ``get`` prints it after the time
    and a tab. A failure is one line on stderr, as in ``run``."""
    prefix = f"repetition {number} at {started}: "
    if output.as_json:
        output.show(outcome, {"repetition": number, "time": started}, prefix)
    elif outcome.ok:
        write_line(f"{started}\t{outcome_text(outcome).plain}")
    else:
        print_error(output.err, error_text(outcome, prefix))


# --------------------------------------------------------------------- watch


def watch_variables(words: list[str]) -> tuple[VarRef, ...]:
    """The variables the words name, in the console's ``watch`` syntax (``P 0``,
    ``IO 128-135``, several in a row); labels and ``every`` are the console's own."""
    variables, rest, _ = parse_var_list(" ".join(words), WATCH_USAGE)
    rest = rest.strip()
    if rest.lower().startswith("every"):
        raise InputError(f"write the period as an option: --every {rest[5:].strip() or '0.5'}")
    if rest:
        raise InputError(f"watch takes variables only, not {rest!r}: {WATCH_USAGE}")
    return variables


@stderr_may_close()
def watch(args: argparse.Namespace) -> ExitStatus:
    """``watch VAR... [--every S] [--count N] [--log-csv FILE]``: one line a cycle until
    N cycles or Ctrl-C, and with --log-csv one CSV row a cycle, as the console logs.

    Ctrl-C is how a watch without --count ends, so it is no failure: the status is
    the worst one seen (0 when every read succeeded). A connection that fails is
    tried again the next cycle, the failure shown in that cycle's line. A CSV log
    that fails is said once and the watch goes on (exit status 4, as for --record).
    """
    output = Output(args.json)
    try:
        common, named = words_by_member(args.variables, args)
        variables = tuple(dict.fromkeys(watch_variables(common))) if common else ()
        by_member = {name: watch_variables(words) for name, words in named.items()}
        if not variables and not any(by_member.values()):
            raise InputError(f"missing variable: {WATCH_USAGE}")
    except InputError as exc:
        print_error(output.err, str(exc))
        return ExitStatus.REFUSED
    from .plant import say_plant_notices

    say_plant_notices(args)
    # Each variable's failure (by target), said on stderr once.
    reported: dict[tuple[str | None, VarRef], str] = {}

    targets = dict(getattr(args, "cell_targets", None) or [(None, args.target)])

    def cycle(name: str | None, number: int, wall: float, results: Results) -> None:
        _report_failures(output, name, results, reported, targets.get(name))
        started = timestamp(wall)
        if output.as_json:
            data = _cycle_json(number, started, results)
            write_line(json.dumps(data if name is None else {"target": name} | data))
        else:
            write_line(_cycle_text(started, results, name))

    return run_live(
        args,
        output,
        variables,
        cycle,
        count=args.count,
        interval=_every(args),
        until_ctrl_c=True,
        log_csv=args.log_csv,
        by_member=by_member,
    )


def _report_failures(
    output: Output,
    name: str | None,
    results: dict[VarRef, Outcome | None],
    reported: dict[tuple[str | None, VarRef], str],
    target: Target | None = None,
) -> None:
    """A failure on stderr when it starts or changes, not every cycle (the cycle's
    line shows it each time); a connection that failed points to ``check``."""
    for var, outcome in results.items():
        if outcome is None:
            continue
        if outcome.ok:
            reported.pop((name, var), None)
            continue
        prefix = f"{var}: " if name is None else f"{name}.{var}: "
        said = error_text(outcome, prefix)
        if reported.get((name, var)) != said:
            reported[name, var] = said
            print_error(output.err, error_text(pointed_to_check(outcome, target), prefix))


def _cycle_text(
    started: str, results: dict[VarRef, Outcome | None], name: str | None = None
) -> str:
    """``TIME<TAB>NAME=VALUE<TAB>...``: fields for ``cut -f``/``awk -F'\\t'`` and
    self-describing for ``grep 'IO130=ON'``, with no header line to skip. A value is
    never split by a tab (tabs in strings are escaped); array elements are joined
    with commas; a failure is ``NAME=!REASON``."""
    fields = [started]
    lead = "" if name is None else f"{name}."  # a cell: cell3.IO128=ON
    for var, outcome in results.items():
        fields.append(f"{lead}{var}={_field(outcome)}")
    return "\t".join(fields)


def _field(outcome: Outcome | None) -> str:
    if outcome is None:
        return "!skipped"
    if not outcome.ok:
        return "!" + _reason(outcome)
    variant, var = outcome.variant, outcome.var
    return (
        "" if variant is None or var is None else ",".join(t for _, t in var.kind.fields(variant))
    )


def _reason(outcome: Outcome) -> str:
    """One word for why a read failed: the HRESULT's name, or what the connection did."""
    if outcome.response is not None and not outcome.response.ok:
        code = outcome.response.code
        return hresult_name(code) or f"0x{code & 0xFFFFFFFF:08X}"
    match outcome.failure:
        case RequestTimeout():
            return "timeout"
        case ConnectFailed():
            return "no-connection"
        case BadReply():
            return "bad-reply"
        case None:
            return "refused"  # nothing was sent
        case _:
            return "disconnected"


def _cycle_json(number: int, started: str, results: dict[VarRef, Outcome | None]) -> dict[str, Any]:
    """``{"time", "cycle", "ok", "values": {NAME: value or null}, "errors": {NAME: why}}``:
    ``jq '.values.IO130'`` reads one variable; ``errors`` holds only the failed ones."""
    values: dict[str, Any] = {}
    errors: dict[str, str] = {}
    for var, outcome in results.items():
        variant = outcome.variant if outcome is not None and outcome.ok else None
        values[str(var)] = variant.to_json() if variant is not None else None
        if outcome is None:
            errors[str(var)] = "not read: the connection failed earlier in this cycle"
        elif not outcome.ok:
            errors[str(var)] = outcome.summary()
    return {"time": started, "cycle": number, "ok": not errors, "values": values, "errors": errors}


def _every(args: argparse.Namespace) -> float:
    """``watch --every S`` (or ``--interval S``, before or after the command): 0.5 s
    unless given, as the console polls."""
    return WATCH_EVERY if args.every is None else float(args.every)
