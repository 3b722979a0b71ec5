"""What a target lets be written, decided before anything is sent.

A target profile says ``writes = "open" | "confirm" | "read-only"`` and may list
``allow`` ranges (``"I 100-199"``, ``"IO 64-71"``): a write outside them is refused
with the rule that refused it. Pure: no file, no socket.

The command language and the variable tables are imported by the checks that use them:
settling a target (the console, before its first paint) needs only the classes here.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

from ..protocol.errors import InputError

if TYPE_CHECKING:
    from ..protocol import VarKind
    from .language import Exchange, VarRef


class Writes(Enum):
    OPEN = "open"  # writes go out as typed (the built-in simulator's mode)
    CONFIRM = "confirm"  # each write asks old → new [y/N] first (the CLI needs --yes)
    READ_ONLY = "read-only"  # only well-formed GETs go out


@dataclass(frozen=True)
class AllowRange:
    """``I 100-199``: the variables of one type a target lets be written."""

    kind: VarKind
    low: int
    high: int

    def covers(self, var: VarRef) -> bool:
        return var.kind is self.kind and self.low <= var.index <= self.high

    def __str__(self) -> str:
        span = str(self.low) if self.low == self.high else f"{self.low}-{self.high}"
        return f"{self.kind.code} {span}"


_RANGE = re.compile(r"\s*([A-Za-z]+)\s*\[?\s*(\d{1,6})\s*(?:-\s*(\d{1,6})\s*)?\]?\s*", re.ASCII)


def parse_allow(text: str) -> AllowRange:
    """``"I 100-199"``, ``"IO 64"``, ``"P[0-9]"``; InputError with how to write it."""
    from ..protocol.variables import KINDS, MAX_INDEX, kind_of

    example = 'write a range as "TYPE FIRST-LAST" or "TYPE INDEX", e.g. "I 100-199", "IO 64"'
    match = _RANGE.fullmatch(text)
    if match is None:
        raise InputError(f"allow {text!r} is not a range: {example}")
    code, first, last = match.group(1).upper(), int(match.group(2)), match.group(3)
    if code not in KINDS:
        raise InputError(f"allow {text!r}: {code} is not a variable type ({' '.join(KINDS)})")
    high = int(last) if last is not None else first
    if high < first or high > MAX_INDEX:
        raise InputError(f"allow {text!r}: indices run from 0 to {MAX_INDEX}, first to last")
    return AllowRange(kind_of(code), first, high)


def written_var(command: Exchange) -> VarRef | None:
    """The variable a command writes: a typed put's, or a raw well-formed
    ``PUT:RC8:<index>:<type>:...`` line's; None for a GET or a line we cannot read."""
    from .language import Put, Raw, VarRef

    if isinstance(command, Put):
        return command.var
    line = command.request.line
    if isinstance(command, Raw) and line.is_put and line.var is not None:
        return VarRef(*line.var)
    return None


@dataclass(frozen=True)
class WritePolicy:
    """A target's rules for writes; the default lets everything out (as before profiles)."""

    writes: Writes = Writes.OPEN
    allow: tuple[AllowRange, ...] | None = None  # None: any variable
    source: str = ""  # where the rules come from, for messages: "profile cell3"

    @property
    def confirms(self) -> bool:
        return self.writes is Writes.CONFIRM

    def refusal(self, command: Exchange) -> str | None:
        """Why ``allow`` keeps this off the wire, or None (read-only is checked apart)."""
        from .language import Get

        if self.allow is None or isinstance(command, Get) or command.request.read_only_safe:
            return None
        var = written_var(command)
        rules = ", ".join(str(rule) for rule in self.allow) or "nothing"
        where = f"{self.source} " if self.source else ""
        if var is None:
            return (
                f"refused: {where}allows writes only to {rules}, and this line is not a "
                "well-formed GET or PUT:RC8:<index>:<type>:<value> it can check (nothing was sent)"
            )
        if any(rule.covers(var) for rule in self.allow):
            return None
        return f"PUT {var} refused: {where}allows writes only to {rules} (nothing was sent)"


#: How strict a mode of writes is: of several profiles at one endpoint, the strictest.
STRICTNESS = {Writes.OPEN: 0, Writes.CONFIRM: 1, Writes.READ_ONLY: 2}


def strictest(policies: Sequence[WritePolicy]) -> WritePolicy:
    """The rules of several profiles at one controller, together: the strictest mode of
    writes, and only the variables every ``allow`` list lets be written. ``source``
    names the profiles that made the rules (``profile ro``, ``profile a + b``)."""
    if len(policies) == 1:
        return policies[0]
    writes = max((p.writes for p in policies), key=STRICTNESS.__getitem__, default=Writes.OPEN)
    lists = [p.allow for p in policies if p.allow is not None]
    allow: tuple[AllowRange, ...] | None = None
    for ranges in lists:
        allow = ranges if allow is None else _both(allow, ranges)
    made = [p for p in policies if p.writes is writes or p.allow is not None]
    names = [p.source.removeprefix("profile ") for p in made if p.source]
    source = f"profile {' + '.join(dict.fromkeys(names))}" if names else ""
    return WritePolicy(writes, allow, source)


def _both(first: tuple[AllowRange, ...], second: tuple[AllowRange, ...]) -> tuple[AllowRange, ...]:
    """The variables both lists of ranges cover."""
    return tuple(
        AllowRange(a.kind, max(a.low, b.low), min(a.high, b.high))
        for a in first
        for b in second
        if a.kind is b.kind and max(a.low, b.low) <= min(a.high, b.high)
    )


@dataclass(frozen=True)
class TargetProfile:
    """A named target from the config file: ``-H cell3`` or ``connect cell3``."""

    name: str
    host: str
    port: int = 5006
    label: str | None = None  # "Cell 3 — welding": shown on the status line and the border
    colour: str | None = None  # a Rich colour name or #rrggbb
    policy: WritePolicy = WritePolicy()
    publish: str | None = None  # mqtt://HOST/PREFIX: its watched values go to the plant
