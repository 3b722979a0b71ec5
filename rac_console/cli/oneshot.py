"""The one-shot commands ``get``, ``put``, ``send`` and ``run``, each returning an exit status."""

from __future__ import annotations

import argparse
import io
import itertools
import json
import sys
from collections.abc import Iterable, Iterator
from contextlib import ExitStack
from dataclasses import replace
from typing import TYPE_CHECKING

from ..commands.argv import exchange_from_words, input_line
from ..commands.language import Command, Latency
from ..commands.outcome import ExitStatus, Outcome, refused, worst
from ..commands.policy import Writes
from ..commands.target import Target
from ..engine import Alert, Feedback, Measured, Message
from ..engine.commands.builtin import BUILTIN
from ..engine.commands.jobs import run_job
from ..engine.commands.session_context import SessionContext
from ..engine.setup.where import Where
from ..present.cell_view import by_target
from ..present.render import (
    error_text,
    make_console,
    notice_text,
    outcome_text,
    print_error,
    print_outcome,
)
from ..protocol import InputError
from ..session import ConnectFailed, Session
from .agent import AgentLines
from .cell import pick_member
from .target import open_session

if TYPE_CHECKING:
    from ..engine.cell.routes import Done, Line


class Output:
    """Where results go: JSON lines, or rich text (plain when not a terminal)."""

    def __init__(self, as_json: bool) -> None:
        self.as_json = as_json
        #: The target the results came from, when a cell is open: named in each of them.
        self.target: str | None = None
        self.out = make_console()
        self.err = make_console(stderr=True)
        self.local_failed = False

    def local_failure(self, message: str) -> None:
        """A local file failed (``--record`` on a full disk): said once, as it happens;
        the work goes on, and the exit status says so at the end."""
        print_error(self.err, message)
        self.local_failed = True

    def alert(self, alert: Alert) -> None:
        """An engine's alert: a local file that failed, or news (the plant's), said
        on stderr without changing the status."""
        if alert.local_failure:
            self.local_failure(alert.text)
        else:
            print_error(self.err, alert.text)

    def status(self, status: ExitStatus) -> ExitStatus:
        """4 when the commands succeeded but a local file failed; a controller or
        connection failure keeps its own status (the file's failure was said already)."""
        return ExitStatus.LOCAL_IO if self.local_failed and status == ExitStatus.OK else status

    def _extra(self, extra: dict[str, object] | None) -> dict[str, object]:
        return (extra or {}) | ({"target": self.target} if self.target is not None else {})

    def say(self, text: str, extra: dict[str, object] | None = None) -> None:
        """What a command said that is no exchange (a line of ``run``)."""
        if self.as_json:
            data = {"ok": True, "message": text} | self._extra(extra)
            sys.stdout.write(json.dumps(data) + "\n")
            sys.stdout.flush()
        else:
            self.out.print(by_target(self.target, notice_text(text)))

    def show(
        self, outcome: Outcome, extra: dict[str, object] | None = None, prefix: str = ""
    ) -> None:
        if self.target is not None:
            prefix = f"{self.target}: {prefix}"
        if self.as_json:
            data = outcome.to_json() | self._extra(extra)
            sys.stdout.write(json.dumps(data) + "\n")
            sys.stdout.flush()
            if not outcome.ok:
                print_error(self.err, error_text(outcome, prefix))
        elif outcome.ok and self.target is not None:
            self.out.print(by_target(self.target, outcome_text(outcome)), soft_wrap=True)
        else:
            print_outcome(self.out, self.err, outcome, prefix)


def _exchange_line(args: argparse.Namespace) -> str:
    """What the user typed, for JSON's ``input``: the command and its words."""
    return input_line(args.command, args.words)


def one_command(args: argparse.Namespace) -> ExitStatus:
    """``get``, ``put`` and ``send``: build from the words, refuse or send, show, exit status.

    The command is built from ``args.words`` as the shell passed them (see
    :func:`rac_console.cli.main.parse_args`), never from a line joined and parsed again.
    """
    output = Output(args.json)
    line = _exchange_line(args)
    writes = False
    try:
        if args.words_problem is not None:
            raise InputError(args.words_problem)
        output.target = pick_member(args)  # a cell: get @cell3 I 10
        command = exchange_from_words(args.command, args.words)
        writes = BUILTIN.traits(command).writes_with(command)
        from .agent import one_line_via_agent

        feedback = one_line_via_agent(args, command, line)
        via_agent = feedback is not None
        if feedback is not None:
            results = _shown(feedback, line)
        else:
            with open_session(args, output.local_failure) as session:
                results = _results(session, command, args, line, Where.COMMAND_LINE)
        outcome = next(r for r in results if isinstance(r, Outcome))  # an exchange has one
    except InputError as exc:
        outcome, via_agent = refused(line, str(exc)), False
    output.show(pointed_to_check(outcome, args.target))
    gone = own_simulator(args.target) and not via_agent  # the agent's simulator keeps it
    if writes and outcome.status is not ExitStatus.REFUSED and gone:
        print_error(output.err, WRITE_GONE)  # stderr only: stdout and --json stay as they are
    return output.status(outcome.status)


#: Said after a write sent to a simulator started for one command: a put then a get, as
#: two commands, would otherwise show the old value with no word why.
WRITE_GONE = (
    "the write is gone when this command ends: it went to a simulator of its own, and the "
    "next command starts a fresh one (keep one with rac-console sim and -H 127.0.0.1, or "
    "send several lines over one session with run -)"
)


def own_simulator(target: Target | None) -> bool:
    """Whether ``target`` is a simulator this command started (no ``-H``, or ``--cell
    demo``), which ends with it."""
    return target is not None and (target.host is None or target.simulated)


def pointed_to_check(outcome: Outcome, target: Target | None) -> Outcome:
    """A connection that failed says which command finds out why, as the console does
    (``rac-console check -H HOST says why``); the built-in simulator has no such step."""
    if not isinstance(outcome.failure, ConnectFailed) or target is None or target.host is None:
        return outcome
    from ..commands.check import check_pointer

    return replace(outcome, error=f"{outcome.error} {check_pointer(target.host, target.port)}")


def _script_lines(source: str) -> Iterator[str]:
    """Lines of FILE, or of stdin read as they come (``run`` is sequential, so a
    blocking read holds nothing up, and Ctrl-C ends it at once)."""
    if source == "-":
        # UTF-8 (a BOM allowed) from a pipe too, as from a file: not the console's code
        # page, which garbles a UTF-8 script on Windows (cp1252).
        buffer = getattr(sys.stdin, "buffer", None)
        stream = (
            io.TextIOWrapper(buffer, encoding="utf-8-sig", errors="surrogateescape")
            if buffer is not None
            else sys.stdin
        )
        yield from iter(stream.readline, "")
        return
    with open(source, encoding="utf-8-sig", errors="surrogateescape") as handle:
        yield from handle


def run_script(args: argparse.Namespace) -> ExitStatus:
    """``run FILE|-``: every line routed by the planner (``@NAME`` and ``use`` in a
    cell), each target over one session. It stops at the first line that fails, says
    which, and exits with its status; ``--keep-going`` runs on and exits with the worst."""
    output = Output(args.json)
    try:
        lines = _script_lines(args.file)
        first = next(lines, None)  # opens the file: a missing one is said before connecting
    except OSError as exc:
        print_error(output.err, f"cannot read {args.file}: {exc.strerror}")
        return ExitStatus.REFUSED
    from ..engine.cell.cell import member_name

    members = getattr(args, "cell_targets", None) or [(member_name(args.target), args.target)]
    numbered = enumerate(itertools.chain([first] if first else [], lines), 1)
    try:
        return output.status(_run_lines(args, output, members, numbered))
    except InputError as exc:
        print_error(output.err, str(exc))
        return ExitStatus.REFUSED


def _show_line(output: Output, results: list[Outcome | Message], number: int) -> ExitStatus:
    """A script line's results shown; their worst status."""
    status = ExitStatus.OK
    for result in results:
        if isinstance(result, Outcome):
            output.show(result, {"line": number}, prefix=f"line {number}: ")
            status = worst([status, result.status])
        else:
            output.say(result.text, {"line": number})
    return status


def _run_lines(
    args: argparse.Namespace,
    output: Output,
    members: list[tuple[str, Target]],
    numbered: Iterator[tuple[int, str]],
) -> ExitStatus:
    """The script's lines in order, each planned and carried out by the executor of
    routes the console's cell uses (:mod:`..engine.cell.routes`), each target's session
    opened when a line first needs it. In a cell, ``--record`` and ``--log`` are one file
    each, every line naming its target."""
    from ..engine.cell.routes import Line, Routes

    single = len(members) == 1
    status = ExitStatus.OK
    keep_going = bool(getattr(args, "keep_going", False))
    with ExitStack() as stack:
        sessions = _Sessions(args, output, members, stack)
        routes = Routes(sessions, members, lambda: BUILTIN, Where.RUN)
        for number, raw_line in numbered:
            line = raw_line.rstrip("\r\n")
            for name, feedback in routes.answer(Line(number, line)).parts:
                output.target = None if single else name
                status = worst([status, _show_line(output, _shown(feedback, line), number)])
            output.target = None
            if status is not ExitStatus.OK and not keep_going:
                print_error(
                    output.err,
                    f"run stopped at line {number}, which failed: nothing after it was run "
                    "(--keep-going runs on)",
                )
                return status
    return status


class _Sessions:
    """``run``'s targets (:class:`~..engine.cell.routes.Targets`): a session each, opened
    when a line first needs it and closed with ``stack``, running a command inline on
    this thread, as the one-shot commands do."""

    def __init__(
        self,
        args: argparse.Namespace,
        output: Output,
        members: list[tuple[str, Target]],
        stack: ExitStack,
    ) -> None:
        from ..engine.files.frame_files import FrameFiles

        self.args, self.output, self.stack = args, output, stack
        self.targets = dict(members)
        self.names = list(self.targets)
        single = len(members) == 1
        # One target keeps its own files, as without a cell; several share one of each.
        self.plain = (
            args
            if single
            else argparse.Namespace(**{**vars(args), "record": None, "transcript": None})
        )
        self.files: FrameFiles | None = None
        if not single:
            self.files = FrameFiles(
                args.record, getattr(args, "transcript", None), output.local_failure
            )
            stack.callback(self.files.close)
        self.sessions: dict[str, Session] = {}
        self.via_agent: dict[str, AgentLines | None] = {}  # looked for once a target

    def run(self, name: str, command: Command, line: Line, done: Done, whole: bool) -> None:
        """Run ``command`` on ``name``'s session now (or through the agent that holds
        it); ``done`` before this returns."""
        if name not in self.via_agent:
            self.via_agent[name] = agent = AgentLines.attach(
                self.plain, self.targets[name], "run", Where.RUN
            )
            if agent is not None:
                self.stack.callback(agent.close)
        agent = self.via_agent[name]
        if agent is not None:
            done(tuple(agent.run(command, line.text or "")))
            return
        if name not in self.sessions:
            session = self.stack.enter_context(
                open_session(self.plain, self.output.local_failure, self.targets[name])
            )
            if self.files is not None:
                place = self.names.index(name) + 1
                session.add_frame_observer(self.files.view(name, place).frame)
            self.sessions[name] = session
        on = argparse.Namespace(**{**vars(self.args), "target": self.targets[name]})
        done(tuple(_feedback(self.sessions[name], command, on, line.text, Where.RUN)))


def _context(session: Session, args: argparse.Namespace) -> SessionContext:
    """The target's rules for a write: with ``--yes`` on a ``confirm`` target, said
    yes ahead (nothing to ask); read back unless ``--no-verify``."""
    rules: Target = args.target
    if args.yes and rules.policy.confirms:
        rules = replace(rules, policy=replace(rules.policy, writes=Writes.OPEN))
    return SessionContext(session, rules, args.verify)


def _results(
    session: Session, what: str | Command, args: argparse.Namespace, line: str, where: Where
) -> list[Outcome | Message]:
    """One line or command through the registry's job runner, as the console runs it,
    and what it said as the command line shows it (:func:`_shown`)."""
    return _shown(_feedback(session, what, args, line, where), line)


def _feedback(
    session: Session,
    what: str | Command,
    args: argparse.Namespace,
    line: str | None,
    where: Where,
) -> list[Feedback]:
    """One line or command run inline by the registry's job runner: its feedback."""
    _, feedback = run_job(BUILTIN, _context(session, args), what, where, line)
    return feedback


def _shown(feedback: Iterable[Feedback], line: str) -> list[Outcome | Message]:
    """Feedback as the command line shows it: the outcomes, a refusal for each error
    (what only runs at a terminal, a line that does not parse), and what else was said;
    nothing for a blank line or a comment."""
    results: list[Outcome | Message] = []
    for item in feedback:
        if isinstance(item, Outcome):
            results.append(item)
        elif isinstance(item, Message) and item.level == "error":
            results.append(refused(line, item.text))
        elif isinstance(item, Message):
            results.append(item)
    return results


def _latency_command(args: argparse.Namespace) -> Latency:
    """``latency 20 I 1`` as in the console, or ``--count 20 --var 'I 1'``: the entry's
    own parser (the console's) for both; the two forms at once are refused, not merged."""
    words = " ".join(args.words)
    options = (args.count, args.var)
    if words and options != (None, None):
        raise InputError(
            "give the count and the variable as words (latency 20 I 1) or as options "
            "(--count 20 --var 'I 1'), not both"
        )
    if not words:
        count = "" if args.count is None else str(max(1, int(args.count)))
        words = f"{count} {args.var or ''}".strip()
    spec = BUILTIN.get("latency")
    assert spec is not None
    command = spec.parse(words)
    assert isinstance(command, Latency)
    return command


def latency(args: argparse.Namespace) -> ExitStatus:
    """``latency``: one summary line (or JSON object); exit 3 when nothing answered."""
    output = Output(args.json)
    try:
        command = replace(_latency_command(args), interval=args.latency_interval or 0.0)
        agent = AgentLines.attach(args, args.target, "latency")
        if agent is not None:  # measured at the agent's end of its one connection
            try:
                longest = command.count * (args.timeout + command.interval)
                feedback = tuple(agent.run(command, "latency", longest=longest))
            finally:
                agent.close()
        else:
            with open_session(args, output.local_failure) as session:
                _, done = run_job(BUILTIN, _context(session, args), command, Where.COMMAND_LINE)
                feedback = tuple(done)
    except InputError as exc:
        print_error(output.err, str(exc))
        return ExitStatus.REFUSED
    measured = next((f for f in feedback if isinstance(f, Measured)), None)
    if measured is None or measured.summary is None:
        for item in feedback:
            if isinstance(item, Message):
                print_error(output.err, item.text)
        return ExitStatus.TRANSPORT
    if args.json:
        data = measured.summary.to_json()
        if (name := getattr(args, "member_name", None)) is not None:
            data = {"target": name} | data
        sys.stdout.write(json.dumps(data) + "\n")
    else:
        output.out.print(notice_text(measured.text))
    return output.status(ExitStatus.OK if measured.summary.count else ExitStatus.TRANSPORT)
