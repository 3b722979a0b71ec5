"""Tab and Shift+Tab in every pane: to the next or the previous one (declared once)."""

from __future__ import annotations

from textual.binding import Binding

from ..present.help_text import PANE_KEYS


def pane_bindings(pane: str) -> list[Binding]:
    """The pane-switching keys of ``pane`` (``log``, ``row``, ``trend``), off the footer."""
    return [
        Binding(
            "tab",
            "app.focus_pane(1)",
            "Next pane",
            tooltip=PANE_KEYS,
            show=False,
            id=f"{pane}-next-pane",
        ),
        Binding(
            "shift+tab",
            "app.focus_pane(-1)",
            "Previous pane",
            tooltip=PANE_KEYS,
            show=False,
            id=f"{pane}-prev-pane",
        ),
    ]
