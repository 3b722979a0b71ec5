"""A write that comes from the plant (an OPC UA client, with ``--opcua-writes``).

It is held to what a typed ``put`` is held to: the value is checked as a typed one
(refused before anything goes out, saying why), then the target's rules (read-only, a
profile's ``allow``); a target whose writes are confirmed takes them only from someone
at a screen who can answer, never from a SCADA tag. What passes runs as one of the
engine's jobs, in turn with the typed lines and the polls, through the job's write gate
(read back unless --no-verify), its frames tagged with where it came from.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import Future
from typing import TYPE_CHECKING, Protocol

from ...commands.exchange_parsers import parse_put
from ...commands.language import VarRef
from ...commands.outcome import ExitStatus, Outcome
from ...protocol import InputError
from ..exchange.gate import rules_refusal

if TYPE_CHECKING:
    from ...commands.language import Command
    from ...commands.target import Target
    from ..published.events import Result

#: The frames of a plant's write carry this (``[OPC UA]`` in the frame log).
OPCUA_SOURCE = "OPC UA"

#: How a write ended, for the client: a status name (OPC UA's) and what was said.
WriteAnswer = tuple[str, str]
#: A plant's write not started (or not sent) within this many seconds is not sent at all:
#: its client is answered within 30 s (plant/opcua_space.py), and never written after.
RUN_WITHIN = 20.0


class Submit(Protocol):
    def __call__(
        self,
        command: Command | str,
        line: str | None = None,
        seq: int | None = None,
        then: Callable[[Result], None] | None = None,
        publish: bool = True,
        source: str | None = None,
        valid: Callable[[], bool] | None = None,
    ) -> int: ...


class PlantWrites:
    """One engine's door for the plant's writes (any thread)."""

    def __init__(self, submit: Submit, rules: Callable[[], Target]) -> None:
        self._submit = submit
        self._rules = rules

    def write(self, var: VarRef, text: str) -> Future[WriteAnswer]:
        """Write ``text`` (as ``put`` takes it) to ``var``; the answer comes once the
        engine has run it (or at once, refused)."""
        answer: Future[WriteAnswer] = Future()
        try:
            put = parse_put(f"{var.kind.code} {var.index} {text}")
        except InputError as exc:
            answer.set_result(("BadTypeMismatch", str(exc)))
            return answer
        rules = self._rules()
        refusal = rules_refusal(rules.policy, rules.read_only, put)
        if refusal is None and rules.policy.confirms:
            refusal = (
                f"{rules.policy.source or 'this target'} asks before each write: "
                "write from the console, where the question can be answered"
            )
        if refusal is not None:
            answer.set_result(("BadUserAccessDenied", refusal))
            return answer

        def done(result: Result) -> None:
            answer.set_result(answer_of(result))

        # Sent only to the target it was meant for (not another opened since with
        # `connect`), and while its client still waits (never after its answer said so).
        until = time.monotonic() + RUN_WITHIN

        def valid() -> bool:
            return self._rules() is rules and time.monotonic() < until

        shown = f"put {var.kind.code} {var.index} {text}   [{OPCUA_SOURCE}]"  # not typed here
        self._submit(put, shown, then=done, source=OPCUA_SOURCE, valid=valid)
        return answer


def answer_of(result: Result) -> WriteAnswer:
    """The client's answer to the job that wrote: Good only when the controller took
    the value and, read back, holds it."""
    outcome = next((item for item in result.feedback if isinstance(item, Outcome)), None)
    if outcome is None:  # not run (nothing sent), or the engine died running it
        said = "; ".join(getattr(item, "text", "") for item in result.feedback) or "not run"
        return ("BadResourceUnavailable" if said.startswith("not run") else "BadTimeout", said)
    if outcome.read_back_error is not None and outcome.response is not None:
        why = outcome.read_back_error
        return ("BadCommunicationError", f"the controller took it, but it was not read back: {why}")
    if outcome.write_unknown:
        return ("BadTimeout", outcome.error or "no answer: the write may have been applied")
    if outcome.status is ExitStatus.REFUSED:
        return ("BadUserAccessDenied", outcome.error or "refused")
    if outcome.status is ExitStatus.TRANSPORT:
        return ("BadCommunicationError", outcome.error or "no connection")
    if outcome.status is ExitStatus.CONTROLLER_ERROR:
        return ("BadDeviceFailure", outcome.error or "the controller answered an error")
    if outcome.verified is False:
        held = outcome.read_back.value if outcome.read_back is not None else None
        return ("BadDeviceFailure", f"written, but read back as {held!r}")
    return ("Good", "written" if outcome.verified else "written (not read back)")
