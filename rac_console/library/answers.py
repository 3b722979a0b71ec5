"""What came of an exchange, as a Python caller takes it: a value, a :class:`Written` or
a :class:`Sent`, or the exception that says what failed and what the controller may hold.

Reads the console's own :class:`~rac_console.commands.outcome.Outcome` (made by the one
write gate, :mod:`rac_console.engine.exchange.gate`): its status, its words and its
read-back, never a second judgement of the wire.
"""

from __future__ import annotations

from ..commands.language import Exchange, Get, VarRef
from ..commands.outcome import ExitStatus, Outcome
from ..engine.exchange.writes import plain_value as said_value
from ..protocol import Variant
from ..session import BadReply, ConnectFailed, NotSent, RequestTimeout
from .errors import (
    ConnectionFailed,
    ControllerError,
    OutcomeUnknown,
    ReadBackMismatch,
    Refused,
    Timeout,
    UnreadableReply,
)
from .results import Sent, Value, Written
from .target import Endpoint, connection_failed
from .values import plain_value, python_value


def value_of(outcome: Outcome, var: VarRef, at: Endpoint) -> Value:
    """A GET's value; the exception for anything but S_OK with one."""
    variant = outcome.variant
    if not outcome.ok or variant is None:
        raise failure(outcome, at)
    return python_value(var.kind, variant)


def written_of(outcome: Outcome, var: VarRef, value: Value, at: Endpoint) -> Written:
    """A PUT's :class:`Written`; the exception, carrying it, when the write failed,
    may have happened unanswered, or is not shown by the read-back."""
    if outcome.status is ExitStatus.REFUSED:
        raise failure(outcome, at)
    written = _written(outcome, var, value)
    if outcome.ok:
        return written
    raise failure(outcome, at, written, writes=True)


def sent_of(outcome: Outcome, command: Exchange, at: Endpoint) -> Sent:
    """A raw line's :class:`Sent`; the exception for anything but a success answer."""
    response = outcome.response
    if not outcome.ok or response is None:
        var, writes = outcome.var, not command.request.read_only_safe
        written = None
        if writes and var is not None and outcome.status is not ExitStatus.REFUSED:
            value = _python(var, outcome.written)
            as_typed = command.request.line.value or ""
            written = _written(outcome, var, as_typed if value is None else value)
        raise failure(outcome, at, written, writes=writes)
    variant = response.variant
    value = None
    if variant is not None:
        kind = command.var.kind if isinstance(command, Get) else None
        line = command.request.line
        if kind is None and line.is_get and line.var is not None:
            kind = VarRef(*line.var).kind
        fits = kind is not None and kind.reply_problem(variant) is None
        value = python_value(kind, variant) if fits and kind is not None else plain_value(variant)
    return Sent(value, response.code, outcome.response_text or "")


def _written(outcome: Outcome, var: VarRef, value: Value) -> Written:
    return Written(
        str(var),
        value,
        _python(var, outcome.before),
        _python(var, outcome.read_back),
        outcome.verified,
    )


def _python(var: VarRef, variant: Variant | None) -> Value | None:
    if variant is None:
        return None
    if var.kind.reply_problem(variant) is not None:
        return plain_value(variant)
    return python_value(var.kind, variant)


def failure(
    outcome: Outcome, at: Endpoint, written: Written | None = None, *, writes: bool = False
) -> Exception:
    """The exception an outcome that is not a success makes, in the console's words.
    ``writes``: the command may write (a put, a raw line but a well-formed GET)."""
    error = outcome.error or outcome.summary()
    response, failed = outcome.response, outcome.failure
    if outcome.status is ExitStatus.REFUSED or isinstance(failed, NotSent):
        return Refused(error)
    if written is not None and response is not None and response.ok:
        # S_OK, but the read-back holds another value, or could not be made.
        return ReadBackMismatch(f"PUT {written.variable}: {error}{_held(outcome)}", written)
    if response is not None:
        text = error if written is None else f"PUT {written.variable}: {error}{_held(outcome)}"
        return ControllerError(text, response.code, written)
    if outcome.write_unknown:  # its error says so, as the console's does
        what = f"PUT {written.variable}" if written is not None else f"'{outcome.request}'"
        return OutcomeUnknown(f"{what}: {error}{_held(outcome)}", written)
    asked = _asked(outcome, writes)
    if isinstance(failed, BadReply):
        return UnreadableReply(
            f"the controller's reply could not be read: {error} (request {asked})", failed.raw
        )
    if isinstance(failed, RequestTimeout):
        return Timeout(f"{error} (request {asked})")
    if isinstance(failed, ConnectFailed):
        return connection_failed(failed, at, message=error)
    return ConnectionFailed(f"{error} (request {asked})")


def _asked(outcome: Outcome, writes: bool) -> str | None:
    """The request a failure that is no unknown write came on: for a write, the read of
    its variable before it (or after the confirm question), the write never sent; else
    the outcome's own."""
    if writes and outcome.var is not None:
        return Get(outcome.var).wire
    return outcome.request


def _held(outcome: Outcome) -> str:
    """``; read back 14``: what the controller held after a write that failed."""
    var = outcome.var
    if var is None or outcome.read_back is None:
        return ""
    return f"; read back {said_value(var, outcome.read_back)}"
