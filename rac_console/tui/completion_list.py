"""The candidates Tab found, listed over the bottom of the panes, right above the
command line.

It floats on a layer of its own, so opening it moves nothing: the command line stays
where it is typed on and the table keeps its rows. It is as high as the list, at most
:data:`~rac_console.present.completion.WHOLE_LIST` lines and never more than the panes'
height (its room, read at each layout, so a resize fits it again); what does not fit is
counted on its last line, and Tab again shows the next page, so every candidate can be
read at any size.
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
        self.room = 0  # the lines it may take, as the last layout found them

    @property
    def is_open(self) -> bool:
        return self.has_class("-visible")

    def show(self, candidates: list[Candidate]) -> None:
        """List ``candidates``; the same ones again (Tab once more on a line it did not
        change) turn to the next page, after the last back to the first."""
        from ..present.completion import next_page

        if self.is_open and candidates == self.candidates:
            self.first = next_page(len(candidates), self.room, self.first)
        else:
            self.candidates, self.first = candidates, 0
        self.add_class("-visible")
        self.refresh(layout=True)

    def hide(self) -> None:
        self.remove_class("-visible")

    def get_content_height(self, container: Size, viewport: Size, width: int) -> int:
        """The page's lines: the panes' height (``container``), at most a screenful of
        its own; a last page that is short takes only its lines."""
        from ..present.completion import WHOLE_LIST, shown_candidates

        self.room = min(container.height, WHOLE_LIST)
        if self.room <= 0 or not self.candidates:
            return 0
        shown, more = shown_candidates(self.candidates, self.room, self.first)
        if not shown:  # the terminal shrank under a later page: the first again
            self.first = 0
            shown, more = shown_candidates(self.candidates, self.room, 0)
        return len(shown) + (1 if more else 0)

    def render(self) -> Text:
        from ..present.completion import completions_text

        if not self.candidates or self.room <= 0:
            return Text()
        return completions_text(self.candidates, self.room, self.first, self.content_size.width)
