"""How a typed name finds a profile, a cell or a cell's target: one rule everywhere.

``-H``, ``--cell``, ``@NAME``, ``use`` and ``connect`` all look names up here: case is
ignored (``-H CELL3`` is ``cell3``), so two names that differ only in case are refused
where they are declared (:func:`case_collision`). Pure.
"""

from __future__ import annotations

from collections.abc import Iterable


def find_name(names: Iterable[str], typed: str) -> str | None:
    """The name among ``names`` that ``typed`` names, in any case; None for none."""
    key = typed.casefold()
    return next((name for name in names if name.casefold() == key), None)


def case_collision(names: Iterable[str]) -> tuple[str, str] | None:
    """Two names that differ only in case (the first pair met), or None."""
    seen: dict[str, str] = {}
    for name in names:
        other = seen.setdefault(name.casefold(), name)
        if other != name:
            return other, name
    return None
