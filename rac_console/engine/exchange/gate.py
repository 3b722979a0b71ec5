"""The write gate: the one object every write to a controller crosses.

A :class:`WriteGate` holds everything a write is held to: the target's rules (its
profiles' ``writes`` and ``allow`` at the endpoint, read-only), what the command sending
it declares of itself (its spec's write trait: a command declared never to write writes
nothing), and the job's own (the confirm answer, the cancel, the value before as the
watch table knows it, whether to read back). :meth:`WriteGate.exchange` takes any GET,
PUT or raw line: a read goes by the read path (:func:`.execute.execute`, which sends
nothing else); a write is checked, sent here (the one place a request that may write
meets the session), read back, and a timeout said as an unknown outcome.

Every front end's writes cross one, made per job from the job's command spec by its
context (:mod:`rac_console.engine.commands.context`): the console's, the REPL's, a
served console's and a CLI watch's (the engine's), ``run``'s and the one-shot commands'
(a plain session's). A handler never holds the session: it gets a
:class:`~.controller.Controller`, which reads, and writes through its job's gate. The
library makes one per connection with :meth:`WriteGate.for_library`.
tests/test_write_gate.py holds that no other code hands the session a request that may
write.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from ...commands.advice import COMMAND_LINE, LIBRARY, Advice
from ...commands.check import check_pointer
from ...commands.language import Exchange, Get, Put, Raw, VarRef
from ...commands.outcome import ExitStatus, Outcome, refused
from ...commands.policy import WritePolicy, Writes, written_var
from ...commands.routing import WriteTrait
from ...commands.target import Target
from ...protocol import Variant
from ...session import ConnectFailed, NotSent, Reply, Session, TransportError
from .execute import execute, named, never, outcome_of, read_only_refusal
from .writes import Confirm, confirmed, no_one_to_ask, nothing_known, read_back, value_of


@dataclass(frozen=True)
class WriteGate:
    """What every write crossing it is held to; :meth:`exchange` sends through it."""

    policy: WritePolicy  # the target's writes and allow (its strictest profile's)
    #: What the command crossing it declares (its spec's traits): NEVER lets no write out.
    declares: WriteTrait
    command: str = ""  # that command's name, for a refusal ("": the library's own calls)
    read_only: bool = False  # --read-only, or the profile's writes = "read-only"
    verify: bool = True  # read every PUT back
    #: A watched variable's value now (no extra GET then).
    known_before: Callable[[VarRef], Variant | None] = nothing_known
    confirm: Confirm | None = None  # None: nobody to ask (the CLI without --yes)
    cancelled: Callable[[], bool] = never  # the job's cancel, asked before each send
    #: How a refusal says to do it instead: the command line's words, or a script's.
    advice: Advice = COMMAND_LINE

    @classmethod
    def for_library(
        cls, target: Target, *, confirm: Confirm | None = None, yes: bool = False
    ) -> WriteGate:
        """The gate of one library connection (``rac.connect``, a member of ``rac.cell``):
        the call :class:`rac_console.library.connection.Connection` makes, once. The
        target's rules as the console holds them; its ``put`` and ``send`` are declared
        to write; ``confirm`` asks a ``confirm`` target's question, and ``yes`` answers
        it ahead, as ``--yes`` does. Read back unless :meth:`without_read_back`. Its
        refusals say what a script passes, not what the command line takes."""
        policy = target.policy
        if yes and policy.confirms:  # said yes ahead, as --yes: nothing to ask
            policy = replace(policy, writes=Writes.OPEN)
        return cls(
            policy, WriteTrait.ALWAYS, read_only=target.read_only, confirm=confirm, advice=LIBRARY
        )

    def without_read_back(self) -> WriteGate:
        """This gate, a PUT not read back (``put(..., verify=False)``, ``--no-verify``)."""
        return replace(self, verify=False)

    def exchange(self, session: Session, command: Exchange, line: str | None = None) -> Outcome:
        """One GET, PUT or raw line over ``session``; never raises for I/O. A read (a
        typed GET, a raw line that is a well-formed GET) goes by the read path; anything
        else may write (a line that does not start with PUT may still write on a lenient
        controller), and goes by the rules."""
        if isinstance(command, Get) or command.request.read_only_safe:
            return execute(session, command, line=line, cancelled=self.cancelled)
        if self.declares is WriteTrait.NEVER:
            return refused(line, self._undeclared(command), command.request.text)
        return self._write(session, command, line)

    def _undeclared(self, command: Put | Raw) -> str:
        """A write from a command whose spec says it never writes: a mistake in that
        command, refused here whatever the target allows."""
        whose = f"the command {self.command!r}" if self.command else "its caller"
        return (
            f"{named(command)} refused at the write gate: {whose} is declared never to "
            "write (writes=NEVER in its spec's traits); nothing was sent"
        )

    def _write(self, session: Session, command: Put | Raw, line: str | None) -> Outcome:
        """One write the way the target allows: refused by its rules before the wire,
        the value before (read, or the watch table's), asked where the target confirms,
        sent, and read back."""
        policy, verify, confirm, cancelled = self.policy, self.verify, self.confirm, self.cancelled
        wire = command.request.text
        if (refusal := rules_refusal(policy, self.read_only, command)) is not None:
            return refused(line, refusal, wire)
        var = written_var(command)
        if var is None:  # a raw line we cannot read: sent as typed, nothing to read back
            if policy.confirms:
                return refused(line, no_one_to_ask("this line", policy, self.advice), wire)
            return self._send(session, command, line)
        if policy.confirms and confirm is None:
            return refused(line, no_one_to_ask(str(var), policy, self.advice), wire)
        written = value_of(command)
        if written is None and (policy.confirms or policy.allow is not None):
            return refused(
                line,
                "refused: the value of this raw PUT cannot be read, so "
                f"{policy.source or 'the target'}'s rules cannot be checked; write it as "
                f"{self.advice.put(var.kind.code, var.index)} (nothing was sent)",
                wire,
            )
        before = self.known_before(var)
        if before is None and (verify or policy.confirms):
            first = execute(session, Get(var), cancelled=cancelled)
            if isinstance(first.failure, NotSent):
                error = f"PUT {var} {first.error}"
                return replace(first, request=wire, error=error, input_line=line)
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
            asked = confirmed(session, var, before, written, command, confirm, line, cancelled)
            if isinstance(asked, Outcome):
                return asked
            before = asked
        outcome = self._send(session, command, line)
        if isinstance(outcome.failure, NotSent):
            return replace(outcome, var=var, before=before, error=f"PUT {var} {outcome.error}")
        outcome = replace(outcome, var=var, written=written, before=before)
        if not verify or isinstance(outcome.failure, ConnectFailed):  # nothing went out
            return outcome
        if cancelled():  # the user said stop: nothing more goes out, not even the GET
            return replace(outcome, read_back_error="not read back: cancelled")
        return read_back(session, outcome, var, written)

    def _send(self, session: Session, command: Put | Raw, line: str | None) -> Outcome:
        """The write itself, once the rules let it out: the one place in the package
        where a request that may write is handed to the session."""
        request = command.request
        try:
            reply: Reply | TransportError = session.exchange(request, cancelled=self.cancelled)
        except TransportError as exc:
            reply = exc
        return outcome_of(command, reply, line, request)


def rules_refusal(policy: WritePolicy, read_only: bool, command: Put | Raw) -> str | None:
    """Why the rules keep ``command`` off the wire before anything is read or asked
    (read-only, a profile's ``allow``), or None: the gate's first step, and the agent's
    for each request a script's connection sends through it."""
    if read_only:
        profile_rule = policy.writes is Writes.READ_ONLY and policy.source
        why = f"{policy.source} is read-only" if profile_rule else "read-only mode is on"
        if (refusal := read_only_refusal(command, why)) is not None:
            return refusal
    return policy.refusal(command)
