"""The read path: one read sent over a session, and every result turned into an Outcome.

Shared by the CLI, ``run``, the library and the engine behind the console and the REPL.
Only a GET goes out here (a ``get``, a raw line that is a well-formed GET, ``latency``'s
and a wait's reads, a write's reads before and after); anything that may write is
refused, nothing sent: a write crosses the write gate
(:class:`~.gate.WriteGate`), the one place a write meets the session.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from ...commands.language import Exchange, Get, Put, VarRef
from ...commands.latency import LatencySummary, summarize
from ...commands.outcome import ExitStatus, Outcome, refused
from ...protocol import describe_hresult, escape_bytes
from ...protocol.hresult import S_OK
from ...protocol.request import Request
from ...protocol.text import terminal_safe
from ...session import (
    BadReply,
    ConnectFailed,
    NotSent,
    Reply,
    RequestTimeout,
    Session,
    TransportError,
)

_OK, _CONTROLLER_ERROR = ExitStatus.OK, ExitStatus.CONTROLLER_ERROR
_new, _set = object.__new__, object.__setattr__

#: Characters of a refused raw line quoted in its refusal.
QUOTED_LINE = 40


def read_only_refusal(command: Exchange, why: str = "read-only mode is on") -> str | None:
    """Why read-only keeps this off the wire, naming what was refused (a PUT, or the
    raw line itself); None for a well-formed GET, the only thing read-only lets out (in
    every front end, and for raw lines alike). ``why``: whose rule it is."""
    return None if command.request.read_only_safe else refusal_of(command, why)


def refusal_of(command: Exchange, why: str) -> str:
    """``command`` refused for ``why``, naming what was refused (:func:`named`)."""
    if command.request.write:
        return f"{named(command)} refused: {why} (nothing was sent)"
    return (
        f"{named(command)} refused: {why}, and only well-formed GET requests go out "
        "(GET:RC8:<index>:<type>:, e.g. GET:RC8:10:I:); nothing was sent"
    )


def named(command: Exchange) -> str:
    """What a refusal names: ``PUT I 10`` (a typed put), ``PUT`` (a raw line that
    starts with PUT), else the raw line itself, quoted, escaped and cut to
    :data:`QUOTED_LINE` characters."""
    request = command.request
    if request.write:
        return f"PUT {command.var}" if isinstance(command, Put) else "PUT"
    text = terminal_safe(request.text)
    if len(text) > QUOTED_LINE:
        text = text[: QUOTED_LINE - 1] + "…"
    return f"'{text}'"


def never() -> bool:
    """The cancel check of a job nobody can cancel."""
    return False


#: Why the read path keeps a write off the wire (a mistake in the code that sent it
#: there: every write is a :class:`~.gate.WriteGate`'s).
NOT_A_READ = "a write goes out only through the write gate"


def execute(
    session: Session,
    command: Exchange,
    *,
    line: str | None = None,
    cancelled: Callable[[], bool] = never,
) -> Outcome:
    """Send one read and describe what came of it; never raises for I/O. A read is a
    typed GET (``GET:RC8:<index>:<type>:`` by construction) or a raw line that is a
    well-formed GET; anything else is refused, nothing sent: reads cannot write.

    ``cancelled`` is the job's cancel, asked right before the request goes out."""
    request = command.request
    if type(command) is not Get and not request.read_only_safe:
        return refused(line, refusal_of(command, NOT_A_READ), request.text)
    try:
        if cancelled is never:
            reply: Reply | TransportError = session.exchange(request)
        else:
            reply = session.exchange(request, cancelled=cancelled)
    except TransportError as exc:
        reply = exc
    return outcome_of(command, reply, line, request)


def outcome_of(
    command: Exchange,
    reply: Reply | TransportError,
    line: str | None = None,
    request: Request | None = None,
) -> Outcome:
    """What came of sending ``command`` (its ``request``, when the caller has it): its
    reply, or how the exchange failed (the engine's poller keeps just that, and a CLI
    watch makes the outcome of it)."""
    if request is None:
        request = command.request
    kind = type(command)
    var = command.var if kind is Get or kind is Put else None  # type: ignore[union-attr]
    if type(reply) is Reply:  # the usual case first: one check
        response = reply.response
        ok = response.code == S_OK
        # Filled in one step, not by the frozen dataclass's ``__init__`` (made on every
        # exchange): the fields an answer sets; the rest (failure, waited, the
        # read-back's) are None from the class's defaults. tests/test_outcome.py holds
        # it equal to ``Outcome(...)`` with the same fields.
        outcome = _new(Outcome)
        _set(
            outcome,
            "__dict__",
            {
                "request": request.text,
                "status": _OK if ok else _CONTROLLER_ERROR,
                "var": var,
                "response_text": reply.raw.decode("ascii"),
                "response": response,
                "rtt": reply.rtt,
                "error": None if ok else f"controller answered {describe_hresult(response.code)}",
                "input_line": line,
                "written": command.value if kind is Put else None,  # type: ignore[union-attr]
            },
        )
        return outcome
    assert isinstance(reply, TransportError)
    return _failed(request, var, reply, line)


def _failed(
    request: Request,
    var: VarRef | None,
    failure: TransportError,
    line: str | None,
) -> Outcome:
    """The Outcome of an exchange that got no trustworthy reply."""
    wire = request.text
    if isinstance(failure, NotSent):
        return Outcome(
            wire, ExitStatus.REFUSED, var, error=str(failure), input_line=line, failure=failure
        )
    message = str(failure)
    # What may write went out (a connection that could not be opened sent nothing).
    unknown = not isinstance(failure, ConnectFailed) and not request.read_only_safe
    if unknown:
        message += f": {_unknown(request, failure)}"
    raw = failure.raw if isinstance(failure, BadReply) else None
    return Outcome(
        wire,
        ExitStatus.TRANSPORT,
        var,
        response_text=escape_bytes(raw) if raw is not None else None,
        error=message,
        input_line=line,
        failure=failure,
        write_unknown=unknown,
    )


def _unknown(request: Request, failure: TransportError) -> str:
    """An unanswered write said as unknown: a timed-out one may still arrive."""
    what = "the PUT may have been applied" if request.write else "the line may have written"
    later = " or may still arrive" if isinstance(failure, RequestTimeout) else ""
    return f"outcome unknown, {what}{later}"


def measure_latency(
    session: Session,
    var: VarRef,
    count: int,
    interval: float,
    cancelled: Callable[[], bool] = never,
) -> LatencySummary:
    """GET one variable ``count`` times, ``interval`` seconds apart (0: back to back),
    or until ``cancelled()`` says to stop.

    Raises ConnectFailed when the controller cannot be reached at all.
    """
    request = Get(var).request
    samples: list[float] = []
    errors = 0
    exchange, keep = session.exchange, samples.append
    asks = cancelled is not never  # the job's cancel, asked before every send
    started = time.perf_counter()
    for n in range(count):
        if asks and cancelled():
            break
        if interval and n:
            time.sleep(interval)
        try:
            reply = exchange(request)
        except ConnectFailed:
            raise
        except TransportError:
            errors += 1
            continue
        if reply.response.code == S_OK:
            keep(reply.rtt)
        else:
            errors += 1
    return summarize(samples, errors, time.perf_counter() - started)
