"""``wait VAR CONDITION after @NAME VAR CONDITION`` in a cell: one target's condition
awaited only once another target's held, and the delay between the two.

The handshake case: robot A raises IO 128 "part placed", robot B should answer on IO 64
and never moves. ``wait IO 64 on within 5 after @robotA IO 128 on`` (on robotB) waits
for robotA's signal, then for robotB's answer, and says how long the answer took, from
the reply that showed the signal to the one that showed the answer (wall clocks of this
machine, each to within one read: reads are at most 10 ms apart).
"""

from __future__ import annotations

from dataclasses import replace

from ...commands.outcome import Outcome
from ..published.events import Feedback, Message


def chained_feedback(
    first_name: str, first: Outcome, second_name: str, second: Outcome | None
) -> tuple[Feedback, ...]:
    """What a chained wait says: both outcomes and the delay; or, when the first
    condition never held (``second`` None), that the second was not waited for."""
    first_waited = first.waited
    condition = first_waited.condition if first_waited is not None else "its condition"
    if second is None:
        return (
            _named(first, first_name),
            Message(
                f"{second_name} was not waited for: {first_name} {condition} did not hold",
                "error",
            ),
        )
    second_waited = second.waited
    if (
        first_waited is None
        or second_waited is None
        or not second_waited.met
        or first_waited.met_at is None
        or second_waited.met_at is None
    ):
        return (first, second)
    delay = second_waited.met_at - first_waited.met_at
    return (
        _named(first, first_name),
        # One delay, said the same on both lines: from the reply that showed the first
        # condition to the one that showed the second (its wait began a moment later).
        _named(second, second_name, seconds=delay),
        Message(
            f"{second_name} {second_waited.condition} {delay:.3f} s after "
            f"{first_name} {first_waited.condition}"
        ),
    )


def _named(outcome: Outcome, name: str, seconds: float | None = None) -> Outcome:
    """``outcome`` with its condition naming its target (``robotA IO128 on``): the two
    lines of a chained wait come from two robots."""
    waited = outcome.waited
    if waited is None:
        return outcome
    timed = waited.seconds if seconds is None else seconds
    return replace(
        outcome, waited=replace(waited, condition=f"{name} {waited.condition}", seconds=timed)
    )


def met(outcome: Outcome | None) -> bool:
    return outcome is not None and outcome.waited is not None and outcome.waited.met
