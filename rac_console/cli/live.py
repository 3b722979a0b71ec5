"""Live values for pipes: ``get ... -r N -i S`` and ``watch VAR...``, one line at a time.

Both run over one session (:func:`.target.open_session`) and send through
:func:`~rac_console.engine.execute.execute`, like ``get`` and ``run``. Every line is
flushed as it is written, so ``| grep --line-buffered`` sees it at once; a reader that
goes away (``| head -3``) ends the command quietly. The exit status is the worst one
seen, as for ``run``.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import io
import json
import os
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any, TextIO, cast

from ..commands.argv import exchange_from_words, input_line
from ..commands.language import Get, VarRef, parse_var_list
from ..commands.outcome import ExitStatus, Outcome, refused, worst
from ..engine.backoff import Backoff
from ..engine.csvlog import CsvLog, timestamp
from ..engine.execute import execute
from ..present.render import error_text, outcome_text, print_error
from ..protocol import InputError, Variant, hresult_name
from ..session import BadReply, ConnectFailed, RequestTimeout, Session
from .oneshot import Output
from .target import open_session

WATCH_USAGE = "rac-console watch TYPE INDEX [TYPE INDEX|TYPE FIRST-LAST]..., e.g. watch IO 128-135"

#: How a write to stdout fails once its reader has gone: EPIPE (BrokenPipeError), and
#: on Windows also EINVAL.
_READER_GONE = {errno.EPIPE, *([errno.EINVAL] if sys.platform == "win32" else [])}


#: watch's default cycle, as the console's poll interval.
WATCH_EVERY = 0.5


class Schedule:
    """When each repetition (or watch cycle) starts: ``interval`` seconds start to start.

    Pure: it is told the clock's readings (``time.monotonic()`` in :func:`run_live`, a
    test's own numbers in test_live_schedule.py). Starts are counted from the previous
    *scheduled* start, so a slow reply does not push the later ones back. A start that
    is already late begins at once and the count goes on from it: missed starts are
    never made up in a burst. After a transport failure the next start waits at least
    the poller's backoff (0.5 s doubling to 5 s), so a controller that is down is not
    asked in a tight loop.
    """

    def __init__(self, interval: float) -> None:
        self.interval = interval
        self._due: float | None = None  # when the next start is due; None: at once
        self._backoff = Backoff()

    def start(self, now: float) -> float:
        """When the next start is, asked at ``now``: when it is due, or ``now`` when
        that has passed. The caller sleeps until then; the start after it is due an
        interval later, however late that sleep wakes."""
        start = now if self._due is None else max(self._due, now)
        self._due = start + self.interval
        return start

    def ended(self, now: float, *, connection_failed: bool) -> None:
        """The requests of the start before ``now`` are done; ``connection_failed``:
        one of them failed on the connection (connect, timeout, bad reply)."""
        if connection_failed:
            due = now if self._due is None else self._due
            self._due = max(due, now + self._backoff.next_delay())
        else:
            self._backoff.good()


def write_line(text: str) -> None:
    """One line on stdout, flushed now, for readers that act line by line."""
    sys.stdout.write(text + "\n")
    sys.stdout.flush()


def _reader_gone(exc: OSError, stream: TextIO | None = None) -> bool:
    """True when the reader of ``stream`` (stdout by default) has gone; the stream then
    points at the null device, so nothing more (Python's last flush at exit included)
    can fail on it."""
    if exc.errno not in _READER_GONE:
        return False
    with contextlib.suppress(OSError, ValueError):  # ValueError: the stream has no descriptor
        null = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, (stream or sys.stdout).fileno())
        finally:
            os.close(null)
    return True


class _Stderr:
    """stderr for a live run, as Rich and ``print`` see it: the real one until its reader
    goes (``2> >(head -1)``), then the null device, and the run goes on with stdout.

    Rich would instead end the process with status 1 (and point stdout at the null
    device too); stdout's lines and the status the run earned matter more than its
    messages. With no stderr at all (None), what is written goes nowhere.
    """

    def __init__(self, real: TextIO | None) -> None:
        self._real = real

    def __getattr__(self, name: str) -> Any:  # encoding, fileno, errors...: the real one's
        if self._real is None:
            raise AttributeError(name)
        return getattr(self._real, name)

    def isatty(self) -> bool:
        return self._real is not None and self._real.isatty()

    def write(self, text: str) -> int:
        with self._unless_gone() as real:
            real.write(text)
        return len(text)

    def flush(self) -> None:
        with self._unless_gone() as real:
            real.flush()

    @contextlib.contextmanager
    def _unless_gone(self) -> Iterator[TextIO]:
        real = self._real if self._real is not None else io.StringIO()
        try:
            yield real
        except OSError as exc:
            if not _reader_gone(exc, real):
                raise


@contextlib.contextmanager
def _stderr_may_close() -> Iterator[None]:
    """Run with stderr as :class:`_Stderr` (as a decorator: the whole command)."""
    with contextlib.redirect_stderr(cast(TextIO, _Stderr(sys.stderr))):
        yield


# ------------------------------------------------------------ the shared loop

Tick = Callable[[Session, int, float, list[ExitStatus]], list[Outcome]]
"""One repetition or cycle: ``tick(session, number, wall_time, seen)`` reads, adds the
statuses to ``seen`` before it prints (a Ctrl-C during the print must not lose them),
prints, and returns the outcomes."""


def run_live(
    args: argparse.Namespace,
    output: Output,
    tick: Tick,
    *,
    count: int | None,
    interval: float,
    until_ctrl_c: bool,
) -> ExitStatus:
    """``count`` ticks (None: without end) over one session, ``interval`` apart.

    The status is the worst one seen. A closed stdout ends it quietly; Ctrl-C ends it
    the same way when ``until_ctrl_c`` (the usual end of a watch), else it goes on up
    to ``main`` (status 130: fewer results than asked for).
    """
    statuses: list[ExitStatus] = []
    schedule = Schedule(interval)
    try:
        with open_session(args, output.local_failure) as session:
            for number in _ticks(count):
                now = time.monotonic()
                start = schedule.start(now)
                if start > now:
                    time.sleep(start - now)
                outcomes = tick(session, number, time.time(), statuses)
                failed = any(o.status == ExitStatus.TRANSPORT for o in outcomes)
                schedule.ended(time.monotonic(), connection_failed=failed)
    except KeyboardInterrupt:
        if not until_ctrl_c:
            raise
    except InputError as exc:  # --record cannot open its file
        print_error(output.err, str(exc))
        return ExitStatus.REFUSED
    except OSError as exc:
        if not _reader_gone(exc):
            raise
    return output.status(worst(statuses))


def _ticks(count: int | None) -> Iterator[int]:
    """Numbers from 1: ``count`` of them, or without end."""
    number = 0
    while count is None or number < count:
        number += 1
        yield number


# ------------------------------------------------------------------ get -r N


@_stderr_may_close()
def repeat_get(args: argparse.Namespace) -> ExitStatus:
    """``get TYPE INDEX -r N [-i S]``: N results, one a line, each with its time."""
    output = Output(args.json)
    line = input_line("get", args.words)
    try:
        if args.words_problem is not None:
            raise InputError(args.words_problem)
        if args.repeat is None:
            raise InputError(
                "-i needs -r N, how many times to read: "
                f"rac-console get {' '.join(args.words) or 'I 0'} -r 10 -i {args.repeat_interval:g}"
            )
        command = exchange_from_words("get", args.words)
    except InputError as exc:
        output.show(refused(line, str(exc)))
        return ExitStatus.REFUSED

    def repetition(
        session: Session, number: int, wall: float, seen: list[ExitStatus]
    ) -> list[Outcome]:
        outcome = execute(session, command, read_only=args.read_only, line=line)
        seen.append(outcome.status)
        _show_repetition(output, outcome, number, timestamp(wall))
        return [outcome]

    interval = args.repeat_interval or 0.0
    return run_live(
        args, output, repetition, count=args.repeat, interval=interval, until_ctrl_c=False
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


@_stderr_may_close()
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
        variables = watch_variables(args.variables)
        log = _csv_log(args.log_csv, variables, output)
    except InputError as exc:
        print_error(output.err, str(exc))
        return ExitStatus.REFUSED
    reported: dict[VarRef, str] = {}  # each variable's failure, said on stderr once

    def cycle(session: Session, number: int, wall: float, seen: list[ExitStatus]) -> list[Outcome]:
        results = _read_cycle(session, variables, args.read_only)
        outcomes = [o for o in results.values() if o is not None]
        seen += [o.status for o in outcomes]
        _report_failures(output, results, reported)
        started = timestamp(wall)
        if output.as_json:
            write_line(json.dumps(_cycle_json(number, started, results)))
        else:
            write_line(_cycle_text(started, results))
        if log is not None:
            log.write(wall, {var: _good_value(outcome) for var, outcome in results.items()})
        return outcomes

    try:
        return run_live(
            args, output, cycle, count=args.count, interval=_every(args), until_ctrl_c=True
        )
    finally:
        if log is not None:
            log.close()


def _csv_log(path: str | None, variables: tuple[VarRef, ...], output: Output) -> CsvLog | None:
    """The ``--log-csv`` log with a column per field of each variable, as the console's
    ``log FILE.csv``: appended to when the file has the same header, refused
    (InputError) when it has other columns or cannot be opened."""
    if path is None:
        return None
    return CsvLog(path, list(dict.fromkeys(variables)), output.local_failure)


def _good_value(outcome: Outcome | None) -> Variant | None:
    """What a CSV row holds of a read: its value, or nothing (an empty cell) when it failed."""
    return outcome.variant if outcome is not None and outcome.ok else None


def _read_cycle(
    session: Session, variables: tuple[VarRef, ...], read_only: bool
) -> dict[VarRef, Outcome | None]:
    """Each variable's outcome; after a connection failure the rest of the cycle is
    not read (None): it would only wait out the same failure once per variable."""
    results: dict[VarRef, Outcome | None] = {}
    broken = False
    for var in variables:
        if broken:
            results[var] = None
            continue
        outcome = execute(session, Get(var), read_only=read_only)
        results[var] = outcome
        broken = outcome.status == ExitStatus.TRANSPORT
    return results


def _report_failures(
    output: Output, results: dict[VarRef, Outcome | None], reported: dict[VarRef, str]
) -> None:
    """A failure on stderr when it starts or changes, not every cycle (the cycle's
    line shows it each time)."""
    for var, outcome in results.items():
        if outcome is None:
            continue
        if outcome.ok:
            reported.pop(var, None)
            continue
        message = error_text(outcome, f"{var}: ")
        if reported.get(var) != message:
            reported[var] = message
            print_error(output.err, message)


def _cycle_text(started: str, results: dict[VarRef, Outcome | None]) -> str:
    """``TIME<TAB>NAME=VALUE<TAB>...``: fields for ``cut -f``/``awk -F'\\t'`` and
    self-describing for ``grep 'IO130=ON'``, with no header line to skip. A value is
    never split by a tab (tabs in strings are escaped); array elements are joined
    with commas; a failure is ``NAME=!REASON``."""
    fields = [started]
    for var, outcome in results.items():
        fields.append(f"{var}={_field(outcome)}")
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
