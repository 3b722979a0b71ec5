"""The command line: history on Up/Down, Tab completion, grey argument hints."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import ClassVar

from textual import events
from textual.binding import Binding, BindingType
from textual.message import Message
from textual.suggester import Suggester
from textual.widgets import Input

from ..commands.completion import Candidate, common_prefix, complete, hint
from ..present.history import History


class HintSuggester(Suggester):
    """Grey text after the cursor: a history line that starts with what is typed
    (Right accepts it), else what the command still needs (never inserted).

    When a history line takes the place, the argument hint goes to ``show_hint``
    so both stay legible.
    """

    def __init__(self, history: History, show_hint: Callable[[str, str], object]) -> None:
        super().__init__(use_cache=False, case_sensitive=True)
        self._history = history
        self._show_hint = show_hint

    async def get_suggestion(self, value: str) -> str | None:
        needs = hint(value)
        for entry in reversed(self._history.entries):
            if entry.startswith(value) and entry != value:
                self._show_hint(value, needs)
                return entry
        self._show_hint(value, "")
        return value + needs if needs else None


class CommandLine(Input):
    #: What ``connect`` completes to besides sim: (profile name, its label), set by the app.
    targets: tuple[tuple[str, str], ...] = ()
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("tab", "complete", "Complete", id="complete"),
        Binding("up", "history(-1)", "History back", show=False, id="history-back"),
        Binding("down", "history(1)", "History forward", show=False, id="history-forward"),
    ]

    class Entered(Message):
        """A line the user entered, taken out of the line the moment Enter was read."""

        def __init__(self, line: str) -> None:
            super().__init__()
            self.line = line

    class Hint(Message):
        """What the command still needs, when a history suggestion holds the grey text."""

        def __init__(self, value: str, text: str) -> None:
            super().__init__()
            self.value = value  # the line it was made for: a late one is ignored
            self.text = text

    class HelpRequested(Message):
        """``?`` typed on an empty line: the app opens the help."""

    class Completions(Message):
        """Several candidates fit: the app lists them with their help."""

        def __init__(self, candidates: list[Candidate]) -> None:
            super().__init__()
            self.candidates = candidates

    def __init__(
        self, history: History, seen: Callable[[], Iterable[tuple[str, int]]], **kwargs: object
    ) -> None:
        suggester = HintSuggester(history, lambda *hint: self.post_message(self.Hint(*hint)))
        # Focus coming back (F6, Enter on a table row) leaves the cursor where it is: a
        # selected line would be replaced whole by the next key typed.
        super().__init__(suggester=suggester, select_on_focus=False, **kwargs)  # type: ignore[arg-type]
        self.history = history
        self._seen = seen
        self._position: int | None = None
        self._draft = ""

    async def _on_key(self, event: events.Key) -> None:
        """Run this line's own key bindings here, in key order.

        Textual runs a binding only after the key has bubbled up to the app, so in a
        burst of keys (a paste, a slow ssh link) the characters typed after Enter,
        Backspace or Tab reach the line before those keys act: Enter then submitted a
        line merged with the next one. Handled here, every key acts in the order typed.
        """
        if event.character == "?" and not self.value:
            event.stop()
            event.prevent_default()
            self.post_message(self.HelpRequested())
            return  # on an empty line ? asks for help; anywhere else it is a character
        if event.is_printable:
            return  # Input inserts it, in order
        for binding in self._bindings.key_to_bindings.get(event.key, ()):
            event.stop()
            event.prevent_default()
            await self.run_action(binding.action)
            return

    def _on_paste(self, event: events.Paste) -> None:
        """A pasted block runs line by line, as if each line were typed and entered:
        every complete line is entered in order, the unfinished last one stays to edit
        (Textual's Input would keep the first line and drop the rest without a word)."""
        event.stop()
        event.prevent_default()
        *complete, tail = event.text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        if complete:
            first = self.value[: self.cursor_position] + complete[0]
            self.value = ""
            for line in (first, *complete[1:]):
                self.post_message(self.Entered(line))
        if tail:
            self.insert_text_at_cursor(tail)

    async def action_submit(self) -> None:
        """Take the line out now, so keys already on their way start a fresh one."""
        line = self.value
        self.value = ""
        self._position = None
        self._draft = ""
        self.post_message(self.Entered(line))

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
        candidates = complete(text, self._seen(), self.targets)
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
