"""A target's colour around the console: a profile's colour and label on the screen's
border, so two consoles on two robots can't be mixed up (the write's question too)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.text import Text
from textual.color import Color
from textual.screen import Screen

from ..present.status import profile_colour

if TYPE_CHECKING:
    from ..engine.published.status import Status


def border_colour(colour: str | None) -> Color | None:
    """A profile's colour for Textual (an ANSI colour stays one); None when nobody knows
    the name: the caller keeps its default."""
    parsed = profile_colour(colour)
    return Color.from_rich_color(parsed) if parsed is not None else None


def mark_target(screen: Screen[None], status: Status) -> None:
    """A profile's colour around the whole console and its label in the border's
    title, so two consoles on two robots can't be mixed up; none without a profile
    (the simulator, a plain host). A colour nobody knows keeps the default one."""
    from ..present.status import target_label

    label = target_label(status)
    screen.set_class(label is not None, "-profile")
    colour = border_colour(status.colour) if label is not None else None
    screen.styles.border = ("heavy", colour) if colour is not None else None
    screen.border_title = Text(f" {label} ") if label is not None else None
