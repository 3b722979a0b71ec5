"""The candidates Tab found, listed over the bottom of the panes, right above the
command line.

It floats on a layer of its own, so opening it moves nothing: the command line stays
where it is typed on and the table keeps its rows. It is as high as the list, at most
:data:`~rac_console.present.completion.WHOLE_LIST` lines and never more than the panes'
room (CSS: ``max-height: 100%`` of the panes); what does not fit is counted on its last
line, and Tab again shows the next page, so every candidate can be read at any size.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.text import Text
from textual.geometry import Size
from textual.widget import Widget

if TYPE_CHECKING:
    from ..present.completion import Candidate


class CompletionList(Widget):
    """Shown by :meth:`show` (the class ``-visible``), hidden by :meth:`hide`; drawn for
    the lines it was given by the layout, whatever the terminal's size."""

    def __init__(self, **kwargs: str | None) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.candidates: list[Candidate] = []
        self.first = 0  # the page shown starts at this candidate

    @property
    def is_open(self) -> bool:
        return self.has_class("-visible")

    def show(self, candidates: list[Candidate]) -> None:
        """List ``candidates``; the same ones again (Tab once more on a line it did not
        change) turn to the next page, after the last back to the first."""
        from ..present.completion import next_page

        if self.is_open and candidates == self.candidates:
            self.first = next_page(len(candidates), self.content_size.height, self.first)
        else:
            self.candidates, self.first = candidates, 0
        self.add_class("-visible")
        self.refresh(layout=True)

    def hide(self) -> None:
        self.remove_class("-visible")

    def get_content_height(self, container: Size, viewport: Size, width: int) -> int:
        """The lines the whole list wants, up to a screenful of its own; the CSS keeps
        it within the panes."""
        from ..present.completion import WHOLE_LIST

        return min(len(self.candidates), WHOLE_LIST)

    def render(self) -> Text:
        """The page for the lines given: a page that no longer fits them (the terminal
        shrank) starts again at the first."""
        from ..present.completion import completions_text, shown_candidates

        room = self.content_size.height
        if not self.candidates or room <= 0:
            return Text()
        if not shown_candidates(self.candidates, room, self.first)[0]:
            self.first = 0
        return completions_text(self.candidates, room, self.first, self.content_size.width)
