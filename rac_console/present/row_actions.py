"""What a key on a watched row turns into: a ``put`` line to edit, an IO toggle.

Pure, shared by any front end with a table. A line made here is exactly what a person
would type: it is parsed back with the command language before it is offered, so a
value that would not round-trip is said so instead of being written as something else.
The command language loads with the first line made: the console holds its toggles
from the start, before its first paint.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..protocol.errors import InputError
from ..protocol.text import scalar_text, terminal_safe

if TYPE_CHECKING:
    from ..commands.language import Put, VarRef
    from ..engine.events import Cycle, Result
    from ..protocol.variant import Variant


def _number_word(value: object) -> str | None:
    from ..protocol.variant import float_text

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
    from ..commands.language import parse_put

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
    from ..commands.language import Put
    from ..protocol.variables import encode_value

    line = toggle_line(var, variant)
    if line is None:
        return None
    value, text = encode_value(var.kind, "off" if variant and variant.value else "on")
    return Put.of(var, value, text), line


@dataclass
class _Pending:
    seq: int
    value: bool
    answered: bool = False
    polls: int = 0


class PendingToggles:
    """IO writes made from the table that have not come back yet: one per row at a time.

    A toggle writes the opposite of the value shown, so a second toggle before the row
    shows the first one's effect would write the same value again (or one nobody
    meant). A row is busy from the key press until the write failed or was read back
    (the read-back shows the row its new value at once); with ``--no-verify``, until a
    poll after it shows the value written, failing that the second cycle that polled
    the row after the reply (the first may have polled it before the write went out).
    """

    def __init__(self) -> None:
        self._rows: dict[VarRef, _Pending] = {}

    def busy(self, var: VarRef) -> bool:
        return var in self._rows

    def start(self, var: VarRef, seq: int, value: bool) -> None:
        self._rows[var] = _Pending(seq, value)

    def forget(self, var: VarRef) -> None:
        self._rows.pop(var, None)

    def declined(self, seq: int) -> None:
        """The user answered No to the toggle ``seq``'s question: nothing is sent, so
        its row is free at once (not when the refusal comes back from the engine)."""
        for var, pending in list(self._rows.items()):
            if pending.seq == seq:
                del self._rows[var]

    def result(self, result: Result) -> bool:
        """The reply to a toggle: True when that row is free again (the write failed)."""
        from ..commands.outcome import Outcome

        for var, pending in self._rows.items():
            if pending.seq == result.seq:
                outcomes = [f for f in result.feedback if isinstance(f, Outcome)]
                if any(f.ok and f.verified is None for f in outcomes):
                    pending.answered = True  # not read back: a poll must show it
                    return False
                del self._rows[var]
                return True
        return False

    def cycle(self, cycle: Cycle) -> bool:
        """A poll cycle: True when a row became free."""
        if not self._rows:
            return False
        freed = False
        for var, variant in cycle.samples:
            pending = self._rows.get(var)
            if pending is None or not pending.answered:
                continue
            pending.polls += 1
            shows = variant is not None and bool(variant.value) == pending.value
            if shows or pending.polls >= 2:
                del self._rows[var]
                freed = True
        return freed
