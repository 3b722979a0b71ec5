"""What happens around a write but the write itself: the confirm question and the read
that checks its answer, the read-back, and the words a write is said in.

The write itself crosses the write gate (:class:`~.gate.WriteGate`), which calls these;
nothing here sends anything but GETs. A controller that answers S_OK and keeps its old
value, or answers an error and writes anyway, is caught by the read-back: the outcome
says what the controller holds now.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from ...commands.advice import Advice
from ...commands.language import Get, Put, Raw, VarRef
from ...commands.outcome import ExitStatus, Outcome, refused
from ...commands.policy import WritePolicy
from ...commands.readback import comparable, same_value
from ...protocol import ProtocolError, Variant
from ...protocol.text import quoted_text
from ...protocol.variant import parse_variant
from ...session import NotSent, RequestTimeout, Session
from .execute import execute

#: Asks whether to write: (the variable, its value now or None, the value to write,
#: the write) -> yes.
Confirm = Callable[[VarRef, Variant | None, Variant, Put | Raw], bool]

NO_ONE_TO_ASK = (
    'PUT {var} refused: {source}asks before every write (writes = "confirm"); '
    "{say_yes} (nothing was sent)"
)


#: Questions asked at most for one write whose value keeps changing while it is asked.
MAX_QUESTIONS = 3


def confirmed(
    session: Session,
    var: VarRef,
    before: Variant | None,
    written: Variant,
    command: Put | Raw,
    confirm: Confirm,
    line: str | None,
    cancelled: Callable[[], bool],
) -> Variant | Outcome | None:
    """Ask; after a yes read the variable again: the value answered about must still be
    the value there, or the yes was for another write, and the question is asked again
    with the value now (at most :data:`MAX_QUESTIONS` times). The value before the write,
    or the Outcome that ends it (no, a failed read, a value that kept changing)."""
    wire = command.request.text
    for _ in range(MAX_QUESTIONS):
        if not confirm(var, before, written, command):
            return refused(line, f"PUT {var} not confirmed: nothing was sent", wire)
        now = execute(session, Get(var), cancelled=cancelled)
        if isinstance(now.failure, NotSent):
            return replace(
                now, request=wire, input_line=line, var=var, error=f"PUT {var} {now.error}"
            )
        if now.status == ExitStatus.TRANSPORT:
            error = f"PUT {var} not sent: reading it again after the question failed: {now.error}"
            return replace(now, request=wire, input_line=line, var=var, error=error)
        held = now.variant if now.ok else None
        if before is None or held is None or same_value(var.kind, before, held):
            return held if held is not None else before
        changed = f"{var} changed from {plain_value(var, before)} to {plain_value(var, held)}"
        before = held
    return refused(
        line,
        f"PUT {var} not sent: {changed} while the question was open, {MAX_QUESTIONS} times",
        wire,
    )


def nothing_known(var: VarRef) -> Variant | None:
    return None


def read_back(session: Session, outcome: Outcome, var: VarRef, written: Variant | None) -> Outcome:
    """The GET after the PUT: what the controller holds now, and whether it is the value
    written. A mismatch after S_OK is a failure (exit 1); after a timeout or an error
    answer the outcome keeps its own status and the read-back says what happened.

    A PUT that timed out may still be on its way (held up on the network, or unread in
    a slow controller's buffer): its read-back says what the controller held then, and
    never whether the write happened (``verified`` stays None, the outcome unknown)."""
    after = execute(session, Get(var))
    if isinstance(outcome.failure, RequestTimeout):
        if not after.ok:
            return replace(outcome, read_back_error=f"read back failed: {after.error}")
        return replace(outcome, read_back=after.variant, verified=None)
    if not after.ok:
        problem = f"read back failed: {after.error}"
        if outcome.ok:
            return replace(outcome, status=after.status, read_back_error=problem, error=problem)
        return replace(outcome, read_back_error=problem)
    held = after.variant
    checkable = written is not None and held is not None and comparable(var.kind, written)
    verified = same_value(var.kind, written, held) if checkable else None  # type: ignore[arg-type]
    if outcome.response is not None and not outcome.response.ok:
        verified = False  # refused: a value that happens to match is not the write's
    outcome = replace(outcome, read_back=held, verified=verified)
    if outcome.ok and verified is False:
        return replace(
            outcome,
            status=ExitStatus.CONTROLLER_ERROR,
            error="S_OK, but the controller holds another value",
        )
    return outcome


def value_of(command: Put | Raw) -> Variant | None:
    """The value a write sends: a typed put's, or the one a raw PUT line carries."""
    if isinstance(command, Put):
        return command.value
    value = command.request.line.value
    try:
        return parse_variant(value) if value is not None else None
    except ProtocolError:
        return None


def plain_value(var: VarRef, variant: Variant) -> str:
    """``14``, ``ON``, ``X 1  Y 2  Z 3``, ``"text"``: a value in a sentence (and the
    confirm question); a string quoted, so an empty one shows."""
    if isinstance(variant.value, str):
        return quoted_text(variant.value)
    fields = var.kind.fields(variant)
    return "  ".join(f"{label} {text}" if label else text for label, text in fields)


def no_one_to_ask(what: str, policy: WritePolicy, advice: Advice) -> str:
    """A write to a ``confirm`` target refused for want of an answer, and how to give
    one ahead in the words of the front end (``advice``)."""
    source = f"{policy.source} " if policy.source else "this target "
    return NO_ONE_TO_ASK.format(var=what, source=source, say_yes=advice.say_yes)
