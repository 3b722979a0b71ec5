"""The command line: history on Up/Down, Tab completion, grey argument hints."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import ClassVar

from textual.binding import Binding, BindingType
from textual.message import Message
from textual.suggester import Suggester
from textual.widgets import Input

from ..commands.completion import Candidate, common_prefix, complete, hint
from ..history import History


class HintSuggester(Suggester):
    """Grey text after the cursor: a history line that starts with what is typed
    (Right accepts it), else what the command still needs (never inserted)."""

    def __init__(self, history: History) -> None:
        super().__init__(use_cache=False, case_sensitive=True)
        self._history = history

    async def get_suggestion(self, value: str) -> str | None:
        for entry in reversed(self._history.entries):
            if entry.startswith(value) and entry != value:
                return entry
        needs = hint(value)
        return value + needs if needs else None


class CommandLine(Input):
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("tab", "complete", "Complete", id="complete"),
        Binding("up", "history(-1)", "History back", show=False, id="history-back"),
        Binding("down", "history(1)", "History forward", show=False, id="history-forward"),
    ]

    class Completions(Message):
        """Several candidates fit: the app lists them with their help."""

        def __init__(self, candidates: list[Candidate]) -> None:
            super().__init__()
            self.candidates = candidates

    def __init__(
        self, history: History, seen: Callable[[], Iterable[tuple[str, int]]], **kwargs: object
    ) -> None:
        super().__init__(suggester=HintSuggester(history), **kwargs)  # type: ignore[arg-type]
        self.history = history
        self._seen = seen
        self._position: int | None = None
        self._draft = ""

    def action_cursor_right(self, select: bool = False) -> None:
        needs = hint(self.value)
        if self.cursor_at_end and needs and self._suggestion == self.value + needs:
            return  # an argument hint describes, it is not text to insert
        super().action_cursor_right(select)

    def action_history(self, step: int) -> None:
        entries = self.history.entries
        if not entries:
            return
        if self._position is None:
            if step > 0:
                return
            self._draft = self.value
            position = len(entries) - 1
        else:
            position = self._position + step
        if position >= len(entries):
            self._position = None
            self.value = self._draft
        else:
            self._position = max(0, position)
            self.value = entries[self._position]
        self.cursor_position = len(self.value)

    def action_complete(self) -> None:
        text = self.value[: self.cursor_position]
        candidates = complete(text, self._seen())
        if not candidates:
            return
        start = len(text) - candidates[0].start
        insert = candidates[0].text + " " if len(candidates) == 1 else common_prefix(candidates)
        if len(insert.rstrip()) >= candidates[0].start:
            self.value = text[:start] + insert + self.value[self.cursor_position :]
            self.cursor_position = start + len(insert)
        if len(candidates) > 1:
            self.post_message(self.Completions(candidates))  # after the Changed it caused

    def remember(self, line: str) -> None:
        self.history.append(line)
        self._position = None
        self._draft = ""
