"""What each command does, run on the engine's thread: one ``case`` per command.

The registry (:mod:`rac_console.commands.registry`) declares a command and its
parser; its behaviour is here. Every problem becomes feedback, never an exception.
"""

from __future__ import annotations

import time

from ..commands.check import check_pointer
from ..commands.language import (
    Command,
    Connect,
    CsvLog,
    Exchange,
    FrameFile,
    Frames,
    Get,
    Help,
    Latency,
    Put,
    Raw,
    SetInterval,
    Simple,
    Step,
    Unwatch,
    VarRef,
    Wait,
    Watch,
    WatchFile,
)
from ..commands.outcome import Outcome
from ..commands.policy import WritePolicy, Writes
from ..commands.profiles import could_be_profile_name, match_profile
from ..commands.registry import help_lines, parse_command
from ..protocol import InputError, Variant
from ..protocol.text import counted, terminal_safe
from ..session import ConnectFailed, Disconnected, Session, TransportError
from ..session.endpoints import addresses
from . import watchlist
from .conditions import wait_for
from .engine import Engine
from .events import OK, ConfirmWrite, Feedback, Message, Result, UiStep, shown_label
from .execute import measure_latency
from .writes import exchange, plain_value

NOT_CONNECTED = (
    "not connected: connect HOST[:PORT], connect PROFILE, or connect sim for the built-in simulator"
)


def handle(engine: Engine, seq: int, what: str | Command) -> None:
    """Parse (once) and run one submitted line or command; the status, then its Result,
    go to the outbox (so a front end showing the result knows the state it left)."""
    command: Command | None = None
    line = what if isinstance(what, str) else None
    engine.begin_command()
    engine.current_seq = seq
    try:
        command = parse_command(what) if isinstance(what, str) else what
        feedback: list[Feedback]
        if seq <= engine.skip_through:
            feedback = [Message("not run: cancelled (Esc, Ctrl+C) before it started", "error")]
        else:
            feedback = run(engine, command, line) if command is not None else []
    except InputError as exc:
        feedback = [Message(str(exc), "error")]
    except Exception as exc:  # a bug must not end the session at the cell
        feedback = [Message(f"internal error: {exc!r}", "error")]
    engine.publish_status(force=True)
    engine.emit(Result(seq, tuple(feedback), line, command))
    engine.flush_events()


def run(engine: Engine, command: Command, line: str | None) -> list[Feedback]:
    match command:
        case Get() | Put() | Raw():
            session = engine.session
            if session is None:
                return [Message(NOT_CONNECTED, "error")]
            if isinstance(command, Get | Put):
                engine.see((command.var,))
            return [_noted(engine, _exchange(engine, session, command, line))]
        case Wait():
            session = engine.session
            if session is None:
                return [Message(NOT_CONNECTED, "error")]
            engine.see((command.var,))
            outcome = wait_for(
                session,
                command,
                line=line,
                read_only=engine.read_only,
                cancelled=lambda: engine.stopping,
                between=engine.poll_until,
            )
            return [_noted(engine, outcome)]
        case CsvLog():
            return [_csv_log(engine, command)]
        case FrameFile():
            return [_frame_file(engine, command)]
        case Frames(on=on):
            return [UiStep.FRAMES_ON if on else UiStep.FRAMES_OFF]
        case Latency(var=var, count=count, interval=interval):
            if engine.session is None:
                return [Message(NOT_CONNECTED, "error")]
            try:
                summary = measure_latency(
                    engine.session, var, count, interval, cancelled=lambda: engine.stopping
                )
            except (ConnectFailed, Disconnected) as exc:
                engine.connect_failed(exc if isinstance(exc, ConnectFailed) else None)
                return [Message(str(exc), "error")]
            return [Message(summary.text(f"GET {var}"))]
        case Watch(vars=variables, label=label, every=every):
            return [_watch(engine, variables, label, every)]
        case Unwatch(vars=variables):
            return [_unwatch(engine, variables)]
        case SetInterval(seconds=seconds):
            engine.interval = seconds
            engine.wake()
            return [Message(f"poll interval {seconds:g} s")]
        case Connect():
            return [_connect(engine, command)]
        case WatchFile():
            return [_watch_file(engine, command)]
        case Help(topic=topic):
            return [Message("\n".join(help_lines(topic)))]
        case Simple(step=step):
            return [_step(engine, step)]
    raise AssertionError(f"no handler for {command!r}")  # the registry and this match agree


def _exchange(engine: Engine, session: Session, command: Exchange, line: str | None) -> Outcome:
    """One exchange; a write by the target's rules: allow, confirm (asked through the
    front end), the value before and the read-back; a watched row shows the value read
    back at once."""

    def known_before(var: VarRef) -> Variant | None:
        row = engine.watch.rows.get(var)
        return row.variant if row is not None and row.status == OK and not row.stale else None

    def confirm(var: VarRef, before: Variant | None, after: Variant, write: Put | Raw) -> bool:
        question = ConfirmWrite(
            engine.current_seq,
            str(var),
            plain_value(var, before) if before is not None else None,
            plain_value(var, after),
            write.request.text,
            engine.target,
            engine.profile.label if engine.profile is not None else None,
        )
        return engine.ask_confirm(question)

    outcome = exchange(
        session,
        command,
        policy=engine.policy,
        read_only=engine.read_only,
        verify=engine.verify,
        known_before=known_before,
        confirm=confirm,
        line=line,
        cancelled=lambda: engine.stopping,
    )
    row = engine.watch.rows.get(outcome.var) if outcome.var is not None else None
    held = outcome.read_back
    if row is not None and held is not None and row.update(held, time.monotonic()):
        engine.show_row(row)
    return outcome


def _noted(engine: Engine, outcome: Outcome) -> Outcome:
    """A typed exchange that got no trustworthy reply is marked in the log (and one that
    found the controller unreachable is no early drop of a connection)."""
    if isinstance(outcome.failure, ConnectFailed):
        engine.connect_failed(outcome.failure)
    if isinstance(outcome.failure, TransportError):
        engine.mark_failure(outcome.failure)
    return outcome


def _step(engine: Engine, step: Step) -> Feedback:
    match step:
        case Step.PAUSE | Step.RESUME:
            engine.set_paused(step is Step.PAUSE)
            return Message("polling paused" if engine.paused else "polling resumed")
        case Step.DISCONNECT:
            engine.close_target()
            for row in engine.watch.mark_all("DISCONNECTED"):
                engine.show_row(row)
            engine.note("disconnected")
            return Message(
                "disconnected: connect HOST[:PORT] or connect PROFILE to talk to a "
                "controller, connect sim for the built-in simulator"
            )
        case Step.CLEAR:
            return UiStep.CLEAR
        case Step.QUIT:
            return UiStep.QUIT


def _watch(
    engine: Engine, variables: tuple[VarRef, ...], label: str, every: float | None
) -> Message:
    added = engine.watch.add(variables, label, every)
    for var in variables:
        engine.show_row(engine.watch.rows[var])
    engine.see(variables)
    engine.wake()
    names = names_text(variables)
    text = f"watching {names}" if added else f"{names} already watched"
    if every is not None:
        text += f", polled every {every:g} s (other rows: interval {engine.interval:g} s)"
    log = engine.csv.log
    if log is not None and not set(variables) <= set(log.variables):
        text += " (not in the CSV log's columns: log stop, then log FILE again to add them)"
    return Message(text)


def _unwatch(engine: Engine, variables: tuple[VarRef, ...]) -> Message:
    absent = [v for v in variables if v not in engine.watch.rows]
    if variables and len(absent) == len(variables):
        return Message(f"{names_text(variables)} not watched: nothing to stop", "error")
    removed = engine.watch.remove(variables)
    engine.outbox.put_removed(removed)
    text = f"stopped watching {counted(len(removed), 'variable')}"
    if absent:
        verb = "was" if len(absent) == 1 else "were"
        text += f" ({names_text(tuple(absent))} {verb} not watched)"
    return Message(text)


def _csv_log(engine: Engine, command: CsvLog) -> Message:
    sink = engine.csv
    current, log = sink.path, sink.log
    if command.stop:
        ended = sink.stop()
        if ended is not None:
            return Message(f"CSV log stopped: {counted(ended.rows, 'row')} in {ended.path}")
        if current is not None:
            return Message(f"CSV log to {current} stopped before its first row")
        return Message("no CSV log to stop", "error")
    if command.path is None:
        if log is not None:
            count = counted(len(log.variables), "variable")
            return Message(f"logging {count} to {log.path}: {counted(log.rows, 'row')} so far")
        if current is not None:
            return Message(f"logging to {current} from the first poll cycle")
        return Message("not logging: log FILE.csv starts a CSV log of the watched values")
    if current is not None:
        return Message(f"already logging to {current}: log stop first", "error")
    try:
        if not engine.watch.rows:
            sink.wait_for_rows(command.path)
            return Message(
                f"logging to {sink.pending} from the first poll cycle: "
                "the variables watched then are its columns"
            )
        started = sink.start(command.path, list(engine.watch.rows))
    except InputError as exc:
        return Message(f"CSV log not started: {exc}", "error")
    if started.failure is not None:  # its header failed: said here, not as an alert too
        return Message(started.failure, "error")
    how = "appending to" if started.appending else "logging to"
    return Message(
        f"{how} {started.path}: {counted(len(started.variables), 'variable')}, "
        "one row per poll cycle (log stop ends it)"
    )


def _frame_file(engine: Engine, command: FrameFile) -> Message:
    """``record FILE`` / ``transcript FILE`` from now on (the interesting moment is rarely
    foreseen at start), ``… stop``, or where frames go now."""
    word = command.kind
    flag = "--record" if word == "record" else "--log"
    running = engine.recorder if word == "record" else engine.transcript
    if command.stop or command.path is None:
        if running is None:
            return Message(f"no {word} running: {word} FILE starts one (as {flag} FILE)")
        if not command.stop:
            return Message(f"{word} to {terminal_safe(running.path)}: {word} stop ends it")
        running.close()
        engine.set_frame_file(word, None)
        return Message(f"{word} stopped: {terminal_safe(running.path)}")
    if running is not None:
        return Message(
            f"{word} already goes to {terminal_safe(running.path)}: {word} stop first", "error"
        )
    try:
        engine.set_frame_file(word, command.path)
    except InputError as exc:
        return Message(str(exc), "error")
    what = "every frame as JSON lines" if word == "record" else "a transcript of every frame"
    return Message(f"{word}: {what} to {terminal_safe(command.path)} ({word} stop ends it)")


def _connect(engine: Engine, command: Connect) -> Message:
    """``connect PROFILE``, ``connect sim`` or ``connect HOST[:PORT]``: the target changes,
    and with it the profile (label, colour) and the write rules: a profile's, the
    simulator's (open), or for a plain host the ones the engine started with. The
    command line's ``--read-only`` stays whatever the target."""
    given = command.port if command.port_given else None
    match = match_profile(engine.profiles, command.host, given, addresses) if command.host else None
    profile = match.profile if match is not None else None
    for notice in match.notices() if match is not None else ():
        engine.alert(notice)
    host, port = command.host, command.port
    if profile is not None and command.host is not None:
        named = profile.name.casefold() == command.host.casefold()
        host = profile.host if named else command.host  # at its address: the address typed
        port = command.port if command.port_given else profile.port
        policy = profile.policy
    else:
        policy = WritePolicy() if host is None else engine.base_policy
    engine.close_target()
    engine.profile, engine.policy = profile, policy
    engine.read_only = engine.base_read_only or policy.writes is Writes.READ_ONLY
    engine.open_target(host, port)
    assert engine.session is not None
    writes = "read-only" if engine.read_only else f"writes {policy.writes.value}"
    try:
        engine.session.connect()
    except (ConnectFailed, Disconnected) as exc:
        if isinstance(exc, ConnectFailed):
            engine.connect_failed(exc)
        text = f"{exc}; will keep retrying while variables are watched"
        text += f" {check_pointer(command.host, given)}"
        if profile is None and command.host and could_be_profile_name(command.host):
            names = ", ".join(sorted(engine.profiles))
            known = f"profiles: {names}" if names else "the config file names none"
            text += f"; no profile named {command.host} ({known})"
        return Message(text, "error")
    if host is None:
        engine.note("connected to the built-in simulator")
        return Message(f"connected to the built-in simulator ({writes})")
    engine.note(f"connected to {host}:{port}")
    if profile is None:
        rules = f" ({writes})" if writes != "writes open" else ""
        return Message(f"connected to LIVE controller {host}:{port}{rules}")
    label = shown_label(profile.label or profile.name)
    allow = profile.policy.allow
    rules = f", allow {', '.join(map(str, allow)) or 'nothing'}" if allow is not None else ""
    return Message(
        f"connected to {label} (profile {profile.name}): LIVE controller {host}:{port}, "
        f"{writes}{rules}"
    )


def _watch_file(engine: Engine, command: WatchFile) -> Message:
    try:
        if command.action == "save":
            saved = [(row.var, row.label, row.every) for row in engine.watch.rows.values()]
            watchlist.save(command.path, saved)
            return Message(f"saved {len(saved)} watched variables to {command.path}")
        rows = watchlist.load(command.path)
    except InputError as exc:
        return Message(str(exc), "error")
    for var, label, every in rows:
        engine.watch.add((var,), label, every)
        engine.show_row(engine.watch.rows[var])
    engine.see([var for var, _, _ in rows])
    engine.wake()
    return Message(f"loaded {len(rows)} watched variables from {command.path}")


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
