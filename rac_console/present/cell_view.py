"""How a cell is shown by every front end: results named by their target, and the
targets completion offers (the badges are :mod:`.cell_status`'s)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.text import Text

from ..protocol.text import terminal_safe

if TYPE_CHECKING:
    from ..engine.cell.cell import Cell


def by_target(name: str | None, text: Text) -> Text:
    """``text`` led by its target's name (``cell4 › ...``), when several are open."""
    if name is None:
        return text
    return Text.assemble((terminal_safe(name), "bold"), " › ", text)


def cell_targets(cell: Cell) -> list[tuple[str, str]]:
    """What ``use`` and ``@`` complete to: each open target, with its label or address
    as the candidate's help; none for a single target."""
    if cell.single:
        return []
    return [
        (
            member.name,
            terminal_safe(member.target.label or f"{member.target.host}:{member.target.port}"),
        )
        for member in cell.members
    ]
