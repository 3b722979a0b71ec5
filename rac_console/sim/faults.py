"""Faults the simulator can inject on purpose: pure settings and a seeded plan.

Every reply draws its fault from :class:`FaultPlan`; the same seed and the same
sequence of requests give the same faults, so a failure seen once can be replayed.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, fields, replace

from ..protocol.hresult import E_INVALIDRCVPACKET, HRESULTS, S_OK

SLOW_SECONDS = 3.0  # "late by more than a typical client timeout" (the default is 2 s)
GARBAGE = b"\xff\xfe#garbled\x00reply"
EXTRA_LINE = b"0,3,424242\r"
ERROR_CODES = sorted(code for code in HRESULTS if code not in (S_OK, E_INVALIDRCVPACKET))
MAX_EXTRA_GAP_MS = 60_000.0
MAX_DELAY_MS = 60_000.0  # delay_ms and jitter_ms: a minute is far past any client's timeout
#: The float settings and their ranges: finite, from 0 to the maximum. inf would hold
#: every reply for ever, nan would make asyncio's timers raise.
FLOAT_RANGES = {
    "delay_ms": (MAX_DELAY_MS, "ms"),
    "jitter_ms": (MAX_DELAY_MS, "ms"),
    "error_rate": (1.0, "(a probability)"),
    "extra_gap_ms": (MAX_EXTRA_GAP_MS, "ms"),
}
UNSET = ("none", "off")  # ``SIM:SET:extra_gap_ms=none``: the extra line back in the reply's write


@dataclass(frozen=True)
class FaultSettings:
    delay_ms: float = 0.0
    jitter_ms: float = 0.0
    slow_every: int = 0
    drop_every: int = 0
    stall_every: int = 0
    garble_every: int = 0
    split: bool = False
    extra_every: int = 0
    # None: the extra line leaves in the reply's own write. A number: it is a write of its
    # own that many ms after the reply (0: straight after), as a peer answering twice sends.
    extra_gap_ms: float | None = None
    error_rate: float = 0.0
    max_sessions: int = 0
    seed: int = 0

    @property
    def active(self) -> bool:
        """True when any reply may be altered (max_sessions, seed and the extra line's gap
        alter none by themselves)."""
        return any(
            getattr(self, f.name)
            for f in fields(self)
            if f.name not in ("max_sessions", "seed", "extra_gap_ms")
        )

    def describe(self) -> str:
        return " ".join(f"{f.name}={getattr(self, f.name)}" for f in fields(self))

    def updated(self, assignments: str) -> FaultSettings:
        """``delay_ms=50,drop_every=7``: a copy with those settings; ValueError if bad."""
        changes: dict[str, object] = {}
        kinds = {f.name: f.type for f in fields(self)}
        for assignment in filter(None, (a.strip() for a in assignments.split(","))):
            name, sep, text = assignment.partition("=")
            name = name.strip().replace("-", "_")
            if not sep or name not in kinds:
                raise ValueError(f"unknown setting {name!r}")
            kind = kinds[name]
            if name == "extra_gap_ms":
                changes[name] = _gap_ms(text)
            elif kind in (bool, "bool"):
                changes[name] = text.strip().lower() in ("1", "true", "on", "yes")
            elif kind in (int, "int"):
                changes[name] = int(text)
            else:
                try:
                    changes[name] = float(text)
                except ValueError:
                    raise ValueError(f"{name}: not a number: {text.strip()!r}") from None
        updated = replace(self, **changes)  # type: ignore[arg-type]
        updated.check()
        return updated

    def check(self) -> None:
        """ValueError naming the setting, unless every value is in its range."""
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in FLOAT_RANGES:
                if value is None and f.name == "extra_gap_ms":
                    continue
                high, unit = FLOAT_RANGES[f.name]
                if not (isinstance(value, (int, float)) and math.isfinite(value)):
                    raise ValueError(f"{f.name}: give 0 to {high:g} {unit}, got {value}")
                if not 0 <= value <= high:
                    raise ValueError(f"{f.name}: give 0 to {high:g} {unit}, got {value:g}")
            elif isinstance(value, int) and not isinstance(value, bool) and value < 0:
                raise ValueError(f"{f.name} cannot be negative")


@dataclass(frozen=True)
class ReplyFault:
    """What happens to one reply."""

    delay: float = 0.0  # seconds before it is sent
    action: str = "send"  # send, drop, stall, garble, error
    error_code: int = 0
    split: bool = False
    extra: bool = False
    extra_gap: float | None = None  # seconds after the reply, in a write of its own; None: with it


class FaultPlan:
    def __init__(self, settings: FaultSettings) -> None:
        self.settings = settings
        self.active = settings.active  # asked on every read: worked out once (frozen settings)
        self._random = random.Random(settings.seed)
        self.replies = 0

    def next(self) -> ReplyFault:
        s = self.settings
        self.replies += 1
        n = self.replies
        delay = s.delay_ms / 1000
        if s.jitter_ms:
            delay = max(0.0, delay + self._random.uniform(-s.jitter_ms, s.jitter_ms) / 1000)
        if _every(n, s.slow_every):
            delay += SLOW_SECONDS
        action, code = "send", 0
        if _every(n, s.drop_every):
            action = "drop"
        elif _every(n, s.stall_every):
            action = "stall"
        elif _every(n, s.garble_every):
            action = "garble"
        elif s.error_rate and self._random.random() < s.error_rate:
            action, code = "error", self._random.choice(ERROR_CODES)
        extra = _every(n, s.extra_every)
        gap = s.extra_gap_ms / 1000 if extra and s.extra_gap_ms is not None else None
        return ReplyFault(delay, action, code, s.split, extra, gap)


def _every(n: int, every: int) -> bool:
    return every > 0 and n % every == 0


def _gap_ms(text: str) -> float | None:
    """``extra_gap_ms=`` text: ms (range-checked by ``check``), or none/off to unset."""
    if text.strip().lower() in UNSET:
        return None
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"extra_gap_ms: not a number of ms: {text.strip()!r}") from None
