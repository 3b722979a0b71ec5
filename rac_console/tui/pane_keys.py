"""Tab and Shift+Tab in every pane: to the next or the previous one (declared once)."""

from __future__ import annotations

from textual.binding import Binding

#: The help's line for Tab and Shift+Tab in a pane (one line for both: the same text).
PANE_KEYS = "Next or previous pane"


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
