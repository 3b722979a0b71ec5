"""The status line widget; its text is made in :mod:`rac_console.present.status`, for
the widget's width: whole fields, built again when the width changes."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from rich.text import Text
from textual import events
from textual.widgets import Static

from ..present.cell_status import Badge, cell_status_text
from ..present.served import SERVED_BADGE
from ..present.status import status_text

if TYPE_CHECKING:
    from ..engine.published.status import Status


class StatusBar(Static):
    """One line; :meth:`show` builds it from the figures for the width it has."""

    def __init__(self, *, id: str | None = None, served: bool = False) -> None:
        super().__init__(id=id)
        #: Served to a browser (``rac-console serve``): the line starts by saying so.
        self.lead = SERVED_BADGE if served else Text()
        self._figures: tuple[Status, float | None, float, tuple[str, float, int] | None] | None
        self._figures = None
        self._badges: list[Badge] = []
        self._cell_running: tuple[str, float, int] | None = None
        self.line = Text()
        #: Said first on the line until ``time.monotonic()`` passes its second item:
        #: what the watchdog did (see watchdog.py).
        self.notice: tuple[Text, float] | None = None

    def say(self, notice: Text, seconds: float) -> None:
        """``notice`` first on the line for ``seconds``."""
        self.notice = (notice, time.monotonic() + seconds)

    @property
    def saying(self) -> bool:
        """A notice is on the line (the clock goes on until it has gone)."""
        return self.notice is not None

    def _lead(self) -> Text:
        if self.notice is not None and time.monotonic() >= self.notice[1]:
            self.notice = None
        if self.notice is None:
            return self.lead
        return self.lead + self.notice[0] + Text(" ")

    def show(
        self,
        status: Status,
        waiting_since: float | None,
        frames_per_second: float,
        running: tuple[str, float, int] | None = None,
    ) -> Text:
        """Build the line for ``status`` (see :func:`.status_text`) to fit this widget;
        repaint only when it changed. Returns the line."""
        self._figures = (status, waiting_since, frames_per_second, running)
        lead = self._lead()
        width = self.content_size.width - len(lead)
        line = lead + status_text(
            status, waiting_since, frames_per_second, running, width=width if width > 0 else None
        )
        if line != self.line:  # an unchanged line costs no repaint
            self.line = line
            # A repaint, not a layout: one line high whatever it says (app.tcss), and a
            # layout of the whole screen 30 times a second under a flood cost keys.
            self.refresh()
        return line

    def show_cell(self, badges: list[Badge], running: tuple[str, float, int] | None = None) -> Text:
        """A cell's line: one badge per target (see :func:`.cell_status_text`)."""
        self._badges, self._cell_running = badges, running
        lead = self._lead()
        width = self.content_size.width - len(lead)
        line = lead + cell_status_text(badges, width if width > 0 else None, running=running)
        if line != self.line:
            self.line = line
            self.refresh()
        return line

    def render(self) -> Text:
        return self.line

    def on_resize(self, event: events.Resize) -> None:
        if self._figures is not None:
            self.show(*self._figures)
        elif self._badges:
            self.show_cell(self._badges, self._cell_running)
