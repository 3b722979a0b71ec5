"""How much polling a session may ask of its controller: a floor on the time between
polls (``interval``, a row's ``every``) and a cap on the rows watched per target.

A console served to a browser is bounded by default: whoever holds the page, read-only
or not, could otherwise poll 4,096 rows back to back (about 11,000 GETs a second from
one session). ``rac-console serve --min-interval S --max-rows N`` sets the bounds, which
reach each session's console in its environment. Everywhere else the operator at the
terminal is the one polling: no bounds. The poller asks before it changes
(:class:`~..polling.poller.Poller`), so every way of adding a row or changing the pace is bounded.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TypeVar

from ...protocol.errors import InputError
from .where import Where

#: A served session's bounds unless ``serve`` says otherwise (docs/cli.md says why).
SERVED_MIN_INTERVAL = 0.5
SERVED_MAX_ROWS = 256
#: How ``serve`` hands its bounds to each session's console.
MIN_INTERVAL_ENV = "RAC_CONSOLE_SERVED_MIN_INTERVAL"
MAX_ROWS_ENV = "RAC_CONSOLE_SERVED_MAX_ROWS"

N = TypeVar("N", int, float)


@dataclass(frozen=True)
class PollBounds:
    """At least ``min_interval`` seconds between polls of a row, at most ``max_rows``
    rows per target (None: no cap)."""

    min_interval: float = 0.0
    max_rows: int | None = None

    def interval_from(self, seconds: float) -> float:
        """The interval a session starts with: ``seconds``, or the floor if higher."""
        return max(seconds, self.min_interval)

    def check_period(self, seconds: float, word: str) -> None:
        """InputError when ``word`` (``interval``, ``every``) ``seconds`` is under the
        floor: it says the floor and how the operator changes it."""
        if seconds < self.min_interval:
            raise InputError(
                f"{word} {seconds:g} is faster than a served console may poll: at least "
                f"{self.min_interval:g} s (the operator sets it: rac-console serve "
                "--min-interval SECONDS)"
            )

    def check_rows(self, watched: int, adding: int) -> None:
        """InputError when ``adding`` rows to the ``watched`` ones passes the cap: it
        says the cap and how the operator changes it."""
        if self.max_rows is not None and watched + adding > self.max_rows:
            raise InputError(
                f"{adding} more row{'s' * (adding != 1)} would make {watched + adding}: a "
                f"served console watches at most {self.max_rows} rows per target "
                f"({watched} now; the operator sets it: rac-console serve --max-rows N)"
            )


UNBOUNDED = PollBounds()


def bounds_for(where: Where, environ: Mapping[str, str] | None = None) -> PollBounds:
    """The bounds of ``where``: a served console's from its environment (set by
    ``serve``; the defaults when missing or not numbers), none elsewhere."""
    if where is not Where.SERVED:
        return UNBOUNDED
    env = os.environ if environ is None else environ
    return PollBounds(
        _number(env.get(MIN_INTERVAL_ENV), float, SERVED_MIN_INTERVAL),
        _number(env.get(MAX_ROWS_ENV), int, SERVED_MAX_ROWS),
    )


def _number(text: str | None, kind: type[N], default: N) -> N:
    """``text`` as a number of ``kind`` from 0 up; ``default`` for anything else (the
    bounds are never lost to a typo)."""
    try:
        value = kind(text) if text is not None else default
    except ValueError:
        return default
    return value if 0 <= value < float("inf") else default


def served_environment(min_interval: float, max_rows: int) -> dict[str, str]:
    """What a session's environment carries of ``serve``'s bounds."""
    return {MIN_INTERVAL_ENV: repr(min_interval), MAX_ROWS_ENV: str(max_rows)}
