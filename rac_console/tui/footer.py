"""The footer: the keys of the focused pane, then the console's, as many as fit whole.

Textual's footer draws every key and lets the line run on under the palette key, so a
narrow terminal showed ``f4 Free▏`` and the first letter of the next key drawn over
(``^p palette3``). This one leaves out, whole, the keys that do not fit, from the last:
the focused pane's come first, then the console's in the order of its bindings (the
help screen and the palette list them all).
"""

from __future__ import annotations

from textual import events
from textual.app import ComposeResult
from textual.widget import Widget
from textual.widgets import Footer

from .compat import (
    footer_key_text,
    footer_ready,
    forget_closed_watchers,
    forget_gone_styles,
    is_palette_key,
)

#: The palette key's width besides its text: the bar at its left.
PALETTE_BAR = 1


def key_width(widget: Widget) -> int:
    """A compact key's cells: ``key description`` and the space after it (0: no key)."""
    text = footer_key_text(widget)
    return 0 if text is None else len(text) + 1


class FittingFooter(Footer):
    """A compact footer that never cuts a key: the ones that do not fit are left out."""

    def __init__(self) -> None:
        super().__init__(compact=True)
        self._width = 0

    def compose(self) -> ComposeResult:
        forget_closed_watchers(self)  # the keys of the last compose, gone (see there)
        forget_gone_styles()  # and their style caches, kept by Textual (see there)
        widgets = list(super().compose())
        width = self.size.width or self.app.size.width
        self._width = width
        keys = [w for w in widgets if not w.has_class("-command-palette")]
        palette = [w for w in widgets if w.has_class("-command-palette")]
        room = width - sum(key_width(w) - 1 + PALETTE_BAR for w in palette if is_palette_key(w))
        for widget in keys:
            need = key_width(widget)
            if need > room:
                break  # the rest are less important: none is shown after a gap
            room -= need
            yield widget
        yield from palette

    def on_resize(self, event: events.Resize) -> None:
        if event.size.width != self._width and footer_ready(self):
            self.call_after_refresh(self.recompose)
