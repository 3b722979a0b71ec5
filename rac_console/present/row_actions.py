"""What a key on a watched row turns into: a ``put`` line to edit, an IO toggle.

Pure, shared by any front end with a table. A line made here is exactly what a person
would type: it is parsed back with the command language before it is offered, so a
value that would not round-trip is said so instead of being written as something else.
The toggles in flight are kept by :class:`~.toggles.PendingToggles`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..commands.exchange_parsers import parse_put
from ..commands.language import Put, VarRef
from ..protocol import Variant
from ..protocol.errors import InputError
from ..protocol.text import scalar_text, terminal_safe
from ..protocol.variables import encode_value
from ..protocol.variant import float_text


def _number_word(value: object) -> str | None:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return float_text(value) if value == value and abs(value) != float("inf") else None
    if isinstance(value, int):
        return str(value)
    return scalar_text(value)  # a Decimal from VT_CY/VT_DECIMAL, as get shows it


def _string_word(value: str) -> str | None:
    """``"text"`` as ``put S`` takes it back (quotes kept off the value), or None."""
    if terminal_safe(value) != value:
        return None  # a control character: not something to put on a command line
    if '"' not in value:
        return f'"{value}"'
    if "'" not in value:
        return f"'{value}'"
    if value and value == value.strip() and value[0] not in "\"'":
        return value  # both quotes inside: taken as typed when it starts with neither
    return None


def value_words(var: VarRef, variant: Variant) -> str | None:
    """The value as ``put`` takes it (``1.5 0 450 180 0 180 5``, ``on``, ``"a b"``)."""
    kind, value = var.kind, variant.value
    if kind.code == "IO":
        return "on" if value else "off"
    if kind.code == "S":
        return _string_word(value) if isinstance(value, str) else None
    if kind.labels:
        if not isinstance(value, list) or len(value) != kind.count:
            return None
        words = [_number_word(v) for v in value]
        return None if None in words else " ".join(w for w in words if w is not None)
    return _number_word(value)


@dataclass(frozen=True, slots=True)
class PutLine:
    """A line for the command line, never sent by itself; ``problem`` says why it holds
    no value (or not the exact one) when so."""

    text: str
    problem: str | None = None


def put_line(var: VarRef, variant: Variant | None) -> PutLine:
    """``put P 10 <its value>``, checked to parse back to the same value."""
    head = f"put {var.kind.code} {var.index} "
    if variant is None:
        return PutLine(head)
    words = value_words(var, variant)
    if words is None:
        return PutLine(head, f"{var}'s value cannot be typed back as it is: type a new one")
    line = head + words
    try:
        written = parse_put(line[4:]).value
    except InputError as exc:
        return PutLine(head, f"{var}'s value cannot be written back: {terminal_safe(str(exc))}")
    same = (
        bool(written.value) == bool(variant.value)
        if var.kind.code == "IO"
        else written.value == variant.value
    )
    if not same:
        nearest = f"{var}: the value on the line is the nearest {var.kind.code} can hold"
        return PutLine(line, nearest)
    return PutLine(line)


def toggle_line(var: VarRef, variant: Variant | None) -> str | None:
    """``put IO 130 off`` for an IO row shown ON; None when there is nothing to toggle."""
    if var.kind.code != "IO" or variant is None:
        return None
    return f"put IO {var.index} {'off' if variant.value else 'on'}"


def toggle_command(var: VarRef, variant: Variant | None) -> tuple[Put, str] | None:
    """Space on an IO row: the write of the opposite of the value shown, made here (the
    engine runs it as it is, never parsing a line back), and how it is shown; None
    when there is nothing to toggle."""
    line = toggle_line(var, variant)
    if line is None:
        return None
    value, text = encode_value(var.kind, "off" if variant and variant.value else "on")
    return Put.of(var, value, text), line


def toggle_refusal(var: VarRef, toggled: object, busy: bool, paused: bool) -> str | None:
    """Why Space on a row sends nothing: not an IO bit, no value read yet, or the last
    toggle not come back (it would toggle from a value already being replaced)."""
    if toggled is None:
        why = "is not an IO row" if var.kind.code != "IO" else "has no value read yet"
        return f"Space toggles an IO bit: {var} {why}; nothing sent"
    if busy:
        wait = " (polling is paused: F2 resumes it)" if paused else ""
        return f"{var}: the last toggle has not come back yet{wait}; nothing sent"
    return None
