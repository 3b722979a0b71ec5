"""A pane's filter line, shown by ``/``: the watch table's and the frame log's."""

from __future__ import annotations

from typing import ClassVar, Protocol

from textual.binding import BindingType
from textual.widget import Widget
from textual.widgets import Input

from . import keys


class Filterable(Protocol):
    """A pane a filter line narrows: it takes the text as typed, and gives it back."""

    @property
    def filter_text(self) -> str: ...

    def set_filter(self, text: str) -> None: ...


class FilterLine(Input):
    """Filters its pane as you type; Enter keeps the filter (the pane's border shows it,
    ``/`` edits it), Esc clears it; both go back to the pane."""

    BINDINGS: ClassVar[list[BindingType]] = keys.FILTER_LINE

    def __init__(self, target: Filterable, placeholder: str, **kwargs: object) -> None:
        super().__init__(placeholder=placeholder, **kwargs)  # type: ignore[arg-type]
        self.target = target

    def on_input_changed(self, event: Input.Changed) -> None:
        event.stop()  # the command line's own handlers are not for this line
        self.target.set_filter(event.value)

    def open(self) -> None:
        """Shown and focused at once: the keys typed right after ``/`` come here."""
        self.value = self.target.filter_text
        self.cursor_position = len(self.value)
        self.add_class("-visible")
        focus_now(self)

    def action_clear(self) -> None:
        self.value = ""
        self.target.set_filter("")
        self.remove_class("-visible")
        self._back()

    def action_done(self) -> None:
        self.remove_class("-visible")
        self._back()

    def _back(self) -> None:
        if isinstance(self.target, Widget):
            focus_now(self.target)


def focus_now(widget: Widget) -> None:
    """Focus at once. ``Widget.focus`` waits behind the keys already queued, so keys
    typed right after F6 (or after a key that leaves a pane) went to the old pane."""
    widget.screen.set_focus(widget)
