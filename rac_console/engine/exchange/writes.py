"""A write, as a careful integrator makes it: refused by the target's rules before the
wire, the value before read (or taken from the watch table), confirmed where the target
asks for it, sent, and read back.

Shared by the CLI, ``run`` and the engine behind the console and the REPL. A controller
that answers S_OK and keeps its old value, or answers an error and writes anyway, is
caught by the read-back: the outcome says what the controller holds now.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from ...commands.check import check_pointer
from ...commands.language import Exchange, Get, Put, Raw, VarRef
from ...commands.outcome import ExitStatus, Outcome, refused
from ...commands.policy import WritePolicy, Writes, written_var
from ...commands.readback import comparable, same_value
from ...protocol import ProtocolError, Variant
from ...protocol.text import quoted_text
from ...protocol.variant import parse_variant
from ...session import ConnectFailed, NotSent, RequestTimeout, Session
from .execute import execute, never, read_only_refusal

#: Asks whether to write: (the variable, its value now or None, the value to write,
#: the write) -> yes.
Confirm = Callable[[VarRef, Variant | None, Variant, Put | Raw], bool]

NO_ONE_TO_ASK = (
    'PUT {var} refused: {source}asks before every write (writes = "confirm"); '
    "add --yes to write from a script or the command line (nothing was sent)"
)


#: Questions asked at most for one write whose value keeps changing while it is asked.
MAX_QUESTIONS = 3


def _confirmed(
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


def _nothing_known(var: VarRef) -> Variant | None:
    return None


@dataclass(frozen=True)
class WriteRules:
    """What a write is held to: the target's rules, and its job's (ask, cancel)."""

    policy: WritePolicy
    read_only: bool = False
    verify: bool = True  # read every PUT back
    #: A watched variable's value now (no extra GET then).
    known_before: Callable[[VarRef], Variant | None] = _nothing_known
    confirm: Confirm | None = None  # None: nobody to ask (the CLI without --yes)
    cancelled: Callable[[], bool] = never  # the job's cancel, asked before each send


def exchange(
    session: Session, command: Exchange, rules: WriteRules, line: str | None = None
) -> Outcome:
    """One GET, PUT or raw line, from any front end: a put, and any raw line but a
    well-formed GET (a line that does not start with PUT may still write on a lenient
    controller), goes by the target's rules (:func:`write`); a read is just sent."""
    if isinstance(command, Put) or (
        isinstance(command, Raw) and not command.request.read_only_safe
    ):
        return write(session, command, rules, line)
    return execute(
        session, command, read_only=rules.read_only, line=line, cancelled=rules.cancelled
    )


def write(session: Session, command: Put | Raw, rules: WriteRules, line: str | None) -> Outcome:
    """Send one write the way the target allows; never raises for I/O."""
    policy, read_only, verify = rules.policy, rules.read_only, rules.verify
    confirm, cancelled = rules.confirm, rules.cancelled
    wire = command.request.text
    if read_only:
        profile_rule = policy.writes is Writes.READ_ONLY and policy.source
        why = f"{policy.source} is read-only" if profile_rule else "read-only mode is on"
        if (refusal := read_only_refusal(command, why)) is not None:
            return refused(line, refusal, wire)
    if (refusal := policy.refusal(command)) is not None:
        return refused(line, refusal, wire)
    var = written_var(command)
    if var is None:  # a raw line we cannot read: sent as typed, nothing to read back
        if policy.confirms:
            return refused(line, _no_one_to_ask("this line", policy), wire)
        return execute(session, command, line=line, cancelled=cancelled)
    if policy.confirms and confirm is None:
        return refused(line, _no_one_to_ask(str(var), policy), wire)
    written = _value_of(command)
    if written is None and (policy.confirms or policy.allow is not None):
        return refused(
            line,
            f"refused: the value of this raw PUT cannot be read, so {policy.source or 'the target'}"
            f"'s rules cannot be checked; write it as put {var.kind.code} {var.index} VALUE "
            "(nothing was sent)",
            wire,
        )
    before = rules.known_before(var)
    if before is None and (verify or policy.confirms):
        first = execute(session, Get(var), cancelled=cancelled)
        if isinstance(first.failure, NotSent):
            return replace(first, request=wire, error=f"PUT {var} {first.error}", input_line=line)
        if first.status == ExitStatus.TRANSPORT:  # the controller does not answer: no PUT
            return replace(
                first,
                request=wire,
                error=f"PUT {var} not sent: reading its value first failed: {first.error}"
                f" {check_pointer(session.host, session.port)}",
                input_line=line,
                var=var,
            )
        before = first.variant if first.ok else None
    if policy.confirms and confirm is not None and written is not None:
        asked = _confirmed(session, var, before, written, command, confirm, line, cancelled)
        if isinstance(asked, Outcome):
            return asked
        before = asked
    outcome = execute(session, command, line=line, cancelled=cancelled)
    if isinstance(outcome.failure, NotSent):
        return replace(outcome, var=var, before=before, error=f"PUT {var} {outcome.error}")
    outcome = replace(outcome, var=var, written=written, before=before)
    if not verify or isinstance(outcome.failure, ConnectFailed):  # nothing went out
        return outcome
    if cancelled():  # the user said stop: nothing more goes out, not even the GET
        return replace(outcome, read_back_error="not read back: cancelled")
    return _read_back(session, outcome, var, written)


def _read_back(session: Session, outcome: Outcome, var: VarRef, written: Variant | None) -> Outcome:
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


def _value_of(command: Put | Raw) -> Variant | None:
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


def _no_one_to_ask(what: str, policy: WritePolicy) -> str:
    source = f"{policy.source} " if policy.source else "this target "
    return NO_ONE_TO_ASK.format(var=what, source=source)
