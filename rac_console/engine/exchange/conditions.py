"""``wait``: read one variable until its condition holds or the time is up.

Shared by ``run`` (over a bare session) and the engine behind the console and the
REPL (which keeps polling the watched rows between the reads).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

from ...commands.conditions import holds
from ...commands.language import Get, Wait
from ...commands.outcome import ExitStatus, Outcome, Waited
from ...protocol import Variant
from ...protocol.text import counted
from ...session import ConnectFailed, Session
from .execute import execute

#: The shortest time between two reads of a wait: at most 100 reads a second, so a
#: wait of minutes does not flood a controller that answers in microseconds.
READ_EVERY = 0.01


def sleep_until(until: float, deadline: float) -> None:
    """The time between two reads with nothing else to do (a plain session's)."""
    time.sleep(max(0.0, until - time.perf_counter()))


def wait_for(
    session: Session,
    wait: Wait,
    *,
    line: str | None = None,
    cancelled: Callable[[], bool] = lambda: False,
    between: Callable[[float, float], None] = sleep_until,
) -> Outcome:
    """Read ``wait.var`` until the condition holds, ``wait.within`` seconds pass, the
    controller cannot be reached, or ``cancelled()``; the last read's outcome, with how
    it went. ``between(until, deadline)`` passes the time to the next read (the engine
    polls the watched rows then, but starts no poll that could outlast the deadline)."""
    get = Get(wait.var)
    started = time.perf_counter()
    deadline = started + wait.within
    first: Variant | None = None
    reads = 0
    while True:
        sent_at = time.perf_counter()
        outcome = execute(session, get, line=line)  # the read path: a GET alone goes out
        reads += 1
        now = time.perf_counter()
        variant = outcome.variant if outcome.ok else None
        if variant is not None:
            if holds(wait, variant, first):
                return _ended(outcome, wait, True, now - started, reads)
            first = first if first is not None else variant
        # Unreachable, refused, or an error answer (no such variable): reading again
        # would only say the same thing, at up to 100 requests a second.
        if isinstance(outcome.failure, ConnectFailed) or outcome.status in (
            ExitStatus.REFUSED,
            ExitStatus.CONTROLLER_ERROR,
        ):
            return _ended(outcome, wait, False, now - started, reads, ended=True)
        if now >= deadline:
            return _ended(outcome, wait, False, now - started, reads)
        if cancelled():
            return _ended(outcome, wait, False, now - started, reads, "wait cancelled")
        between(min(sent_at + READ_EVERY, deadline), deadline)


def _ended(
    outcome: Outcome,
    wait: Wait,
    met: bool,
    seconds: float,
    reads: int,
    why: str | None = None,
    *,
    ended: bool = False,
) -> Outcome:
    waited = Waited(wait.condition, met, seconds, reads, wait.within, time.time() if met else None)
    if met:
        return replace(outcome, waited=waited)
    # Not met: the last read's own failure says most; else the condition is the error.
    status = outcome.status if not outcome.ok else ExitStatus.CONTROLLER_ERROR
    if ended:  # the read's failure ended the wait before its time
        error = f"{wait.condition}: wait ended after {counted(reads, 'read')}: "
        error += outcome.error or ""
        return replace(outcome, status=status, error=error, waited=waited)
    error = why or waited.text()
    if outcome.error:
        error += f"; the last read failed: {outcome.error}"
    return replace(outcome, status=status, error=error, waited=waited)
