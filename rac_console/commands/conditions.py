"""``wait`` and ``log``: their parsers, and when a wait's condition holds.

Pure: nothing here reads the wire. The engine and ``run`` read the variable and ask
:func:`holds` about each value read.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace

from ..protocol import InputError, Variant
from ..protocol.variables import encode_value
from .language import (
    After,
    CsvLog,
    Op,
    Wait,
    parse_seconds,
    parse_var,
)

WAIT_USAGE = (
    "wait TYPE INDEX CONDITION [within SECONDS], e.g. wait IO 128 on within 2, "
    "wait I 10 >= 100 within 30, wait P 0 changes within 5"
)
#: How long a wait without ``within`` waits: never for ever, next to machinery.
DEFAULT_WITHIN = 10.0
NUMERIC_KINDS = ("I", "F", "D")

_OPERATOR_RE = re.compile(r"(==|=|!=|<=|>=|<|>)\s*(.*)", re.DOTALL)
_WITHIN_RE = re.compile(r"(.*?)\s*\bwithin\s+(\S+?)s?", re.ASCII | re.DOTALL | re.IGNORECASE)


_AFTER_RE = re.compile(r"\s+after\s+@(\S+)\s+(.+)", re.ASCII | re.DOTALL | re.IGNORECASE)


def _after_at(text: str) -> re.Match[str] | None:
    """The last `` after @NAME ...`` outside quotes: a string value in quotes may hold
    those words (``wait S 1 == "x after @B I 11 == 78"``)."""
    found, quote = None, ""
    for at, char in enumerate(text):
        if quote:
            quote = "" if char == quote else quote
        elif char in "\"'":
            quote = char
        elif char.isspace() and (match := _AFTER_RE.match(text, at)) is not None:
            found = match
    return found


def parse_wait(rest: str) -> Wait:
    """``wait VAR CONDITION [within S]``, and in a cell ``... after @NAME VAR CONDITION``:
    each condition waits up to S seconds, the second from when the first held."""
    text = rest.strip()
    chained = _after_at(text)
    if chained is not None:
        first = _parse_one(chained.group(2))
        second = _parse_one(text[: chained.start()])
        if _WITHIN_RE.fullmatch(chained.group(2).strip()) is None:
            first = replace(first, within=second.within)
        return replace(second, after=After(chained.group(1), first))
    return _parse_one(rest)


def _parse_one(rest: str) -> Wait:
    var, after = parse_var(rest, WAIT_USAGE)
    condition, within = after.strip(), DEFAULT_WITHIN
    match = _WITHIN_RE.fullmatch(condition)
    if match:
        condition, within = match.group(1).strip(), parse_seconds(match.group(2), "within")
    if not condition:
        raise InputError(f"wait needs a condition: {WAIT_USAGE}")
    word = condition.lower()
    if word in ("on", "off"):
        if var.kind.code != "IO":
            raise InputError(
                f"on and off are for IO bits; compare {var} with a value: wait {var} == 1"
            )
        return Wait(var, Op.ON if word == "on" else Op.OFF, None, within)
    if word == "changes":
        return Wait(var, Op.CHANGES, None, within)
    operator = _OPERATOR_RE.fullmatch(condition)
    if operator is None:
        raise InputError(
            f"unknown condition {condition!r}: use on, off, changes, or == != < <= > >= "
            f"and a value ({WAIT_USAGE})"
        )
    symbol, value_text = operator.group(1), operator.group(2).strip()
    op = Op.EQ if symbol == "=" else Op(symbol)
    if not value_text:
        raise InputError(f"{symbol} needs a value: wait {var} {symbol} 100")
    if op in (Op.EQ, Op.NE):
        variant, _ = encode_value(var.kind, value_text)  # refused as a put would be
        return Wait(var, op, variant, within, value_text)
    if var.kind.code not in NUMERIC_KINDS:
        raise InputError(
            f"{symbol} compares numbers (I F D); wait for {var} with ==, != or changes"
        )
    return Wait(var, op, _number(value_text, symbol), within, value_text)


_NUMBER_RE = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)


def _number(text: str, symbol: str) -> float:
    """A plain decimal number (no ``1_000``, no hex), finite."""
    value = float(text) if _NUMBER_RE.fullmatch(text) else math.nan
    if not math.isfinite(value):
        raise InputError(f"{symbol} needs one number, e.g. >= 100, got {text!r}")
    return value


def holds(wait: Wait, variant: Variant, first: Variant | None) -> bool:
    """Whether the value read meets the condition (``first``: the first value read,
    which ``changes`` compares with)."""
    value = variant.value
    match wait.op:
        case Op.ON | Op.OFF:
            return isinstance(value, bool | int) and bool(value) == (wait.op is Op.ON)
        case Op.CHANGES:
            return first is not None and value != first.value
        case Op.EQ | Op.NE:
            assert isinstance(wait.value, Variant)
            return bool(value == wait.value.value) == (wait.op is Op.EQ)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    threshold = wait.value
    assert isinstance(threshold, float)
    match wait.op:
        case Op.LT:
            return value < threshold
        case Op.LE:
            return value <= threshold
        case Op.GT:
            return value > threshold
        case _:
            return value >= threshold


def parse_log(rest: str) -> CsvLog:
    """``log FILE.csv`` starts, ``log stop`` stops, ``log`` says where it goes."""
    text = rest.strip()
    if not text:
        return CsvLog(None)
    if text.lower() == "stop":
        return CsvLog(None, stop=True)
    return CsvLog(text)
