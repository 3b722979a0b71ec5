"""The IO toggles made from a table that have not come back yet: one per row at a time.

Apart from the lines a key makes (:mod:`.row_actions`), which load the command
language: the console holds its toggles from the start, before its first paint.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..commands.language import VarRef
    from ..engine.published.events import Cycle, Result


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
