"""The command line: history on Up/Down, Tab completion, grey argument hints.

Completion and hints read the command registry, loaded at the first key that needs
them: the console paints its command line before any command is loaded.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, ClassVar

from textual import events
from textual.binding import BindingType
from textual.message import Message
from textual.suggester import Suggester
from textual.widgets import Input

from ..commands.line import MAX_LINE
from . import keys
from .compat import input_suggestion, key_bindings

if TYPE_CHECKING:
    from ..present.completion import Candidate
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
        from ..present.completion import hint

        needs = hint(value)
        entry = self._history.suggest(value)  # never a line refused in this session
        if entry is not None:
            self._show_hint(value, needs)
            return entry
        self._show_hint(value, "")
        return value + needs if needs else None


class CommandLine(Input):
    """The line, its history, completion and hints; and the keys typed ahead of a
    write's question.

    On a ``confirm`` target a write stops to ask, and a ``y`` and an Enter typed right
    after its Enter (muscle memory, a slow link) must neither answer the question nor run
    as a command once it is answered. So the keys that follow the Enter of a line that
    may ask are held here, in the order typed, until the console says how the line went
    (messages, so they are handled in their place among the keys): it asked
    (:class:`Asked`: the keys held are dropped, and the ones still coming until the
    question is answered), the question was answered (:class:`Answered`: keys are held
    again, for a question asked once more), or the line ended (:class:`Release`: the
    keys held are typed in as if they came now). Esc and the console's keys pass.
    """

    #: What ``connect`` completes to besides sim: (profile name, its label), set by the console.
    targets: tuple[tuple[str, str], ...] = ()
    #: A cell's targets (name, label): ``use NAME`` and ``@NAME`` complete to them.
    cell: tuple[tuple[str, str], ...] = ()
    BINDINGS: ClassVar[list[BindingType]] = keys.COMMAND_LINE

    class Hint(Message):
        """What the command still needs, when a history suggestion holds the grey text."""

        def __init__(self, value: str, text: str) -> None:
            super().__init__()
            self.value = value  # the line it was made for: a late one is ignored
            self.text = text

    class HelpRequested(Message):
        """``?`` typed on an empty line: the console opens the help."""

    class Completions(Message):
        """Several candidates fit: the console lists them with their help."""

        def __init__(self, candidates: list[Candidate]) -> None:
            super().__init__()
            self.candidates = candidates

    class Asked(Message):
        """(console → line) The held line asked: drop the keys typed ahead of its question."""

    class Answered(Message):
        """(console → line) Its question was answered: hold keys again until it ends."""

    class Release(Message):
        """(console → line) The held line ended: type in the keys held, stop holding."""

    class Dropped(Message):
        """(line → console) Keys typed ahead of a question were dropped: say how many."""

        def __init__(self, count: int) -> None:
            super().__init__()
            self.count = count

    class TooLong(Message):
        """(line → console) Characters were typed or pasted past :data:`MAX_LINE`: the
        console asks :meth:`refused` how many (one line for a burst of them)."""

    def __init__(
        self, history: History, seen: Callable[[], Iterable[tuple[str, int]]], **kwargs: object
    ) -> None:
        suggester = HintSuggester(history, lambda *hint: self.post_message(self.Hint(*hint)))
        # Focus coming back (F6, Enter on a table row) leaves the cursor where it is: a
        # selected line would be replaced whole by the next key typed.
        super().__init__(
            suggester=suggester,
            select_on_focus=False,
            max_length=MAX_LINE,
            **kwargs,  # type: ignore[arg-type]
        )
        self.history = history
        self._seen = seen
        self._position: int | None = None
        self._draft = ""
        #: Hands a line to the console the moment Enter is read (set by the console),
        #: in the order typed; ``may_hold``: a line typed (not pasted) whose keys after
        #: it may be held. True: it may stop to ask before it writes, so the keys typed
        #: after its Enter are held (the console read that from the route its cell
        #: planned the line to, not from a plan of its own).
        self.enter: Callable[[str, bool], bool] = lambda line, may_hold: False
        self._held: list[events.Key | events.Paste] | None = None  # None: not holding
        self._dropping = False  # a question is up: keys typed ahead of it are dropped
        self._dropped = 0
        self._refused = 0  # characters not taken: the line was full

    def replace(self, text: str, start: int, end: int) -> None:
        """Textual's, with the text cut to what the line still has room for: a key
        past :data:`MAX_LINE` costs nothing (a value is not made to be refused), and the
        console is told once for a burst of them."""
        value = self.value
        start, end = sorted((max(0, start), min(len(value), end)))
        room = MAX_LINE - (len(value) - (end - start))
        if len(text) > room:
            if not self._refused:
                self.post_message(self.TooLong())
            self._refused += len(text) - max(room, 0)
            text = text[: max(room, 0)]
            if not text and start == end:
                return
        super().replace(text, start, end)

    def refused(self) -> int:
        """How many characters were not taken since it was last asked."""
        count, self._refused = self._refused, 0
        return count

    def hold(self) -> None:
        """Hold the keys that come from now (a write started by a key elsewhere)."""
        if self._held is None:
            self._held, self._dropping, self._dropped = [], False, 0

    def _take(self, event: events.Key | events.Paste) -> bool:
        """Hold (or drop) a key or a paste while a line that may ask runs: True if taken."""
        held = self._held
        if held is None:
            return False
        if isinstance(event, events.Key) and not (
            event.is_printable or bool(key_bindings(self, event.key))
        ):
            return False  # Esc, F-keys: the console's, at once
        if self._dropping:
            self._dropped += 1
        else:
            held.append(event)
        return True

    def type_ahead(self, character: str) -> None:
        """A character typed elsewhere that belongs here (the table hands them over):
        held like a key typed here while a line that may ask runs."""
        if not self._take(events.Key(character, character)):
            self.insert_text_at_cursor(character)

    def on_command_line_asked(self, event: Asked) -> None:
        event.stop()
        if self._held is not None:
            self._dropped += len(self._held)
            self._held.clear()
            self._dropping = True

    def on_command_line_answered(self, event: Answered) -> None:
        event.stop()
        if self._held is not None:
            self._dropping = False
            self._say_dropped()

    async def on_command_line_release(self, event: Release) -> None:
        """Type the held keys in, in order, before any key that comes after them."""
        event.stop()
        held, self._held, self._dropping = self._held or [], None, False
        self._say_dropped()
        for key in held:
            if self._take(key):
                continue  # a line typed in just now may ask in turn: held again
            if isinstance(key, events.Paste):
                self._paste(key.text)
            else:
                await self._act(key)

    def _say_dropped(self) -> None:
        if self._dropped:
            self.post_message(self.Dropped(self._dropped))
            self._dropped = 0

    async def on_key(self, event: events.Key) -> None:
        """Run this line's own key bindings here, in key order.

        Textual runs a binding only after the key has bubbled up to the app, so in a
        burst of keys (a paste, a slow ssh link) the characters typed after Enter,
        Backspace or Tab reach the line before those keys act: Enter then submitted a
        line merged with the next one. Handled here, every key acts in the order typed.
        """
        if self._take(event):
            event.stop()
            event.prevent_default()
            return
        if event.character == "?" and not self.value:
            event.stop()
            event.prevent_default()
            self.post_message(self.HelpRequested())
            return  # on an empty line ? asks for help; anywhere else it is a character
        if event.is_printable:
            return  # Input inserts it, in order
        for binding in key_bindings(self, event.key):
            event.stop()
            event.prevent_default()
            await self.run_action(binding.action)
            return

    async def _act(self, event: events.Key) -> None:
        """A held key, typed in now: what it would have done when it came."""
        if event.character == "?" and not self.value:
            self.post_message(self.HelpRequested())
        elif event.is_printable and event.character:
            self.insert_text_at_cursor(event.character)
        else:
            for binding in key_bindings(self, event.key):
                await self.run_action(binding.action)
                return

    def on_paste(self, event: events.Paste) -> None:
        """A pasted block runs line by line, as if each line were typed and entered:
        every complete line is entered in order, the unfinished last one stays to edit
        (Textual's Input would keep the first line and drop the rest without a word)."""
        event.stop()
        event.prevent_default()
        if not self._take(event):
            self._paste(event.text)

    def _paste(self, text: str) -> None:
        *complete, tail = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        if complete:
            first = self.value[: self.cursor_position] + complete[0]
            self.value = ""
            for line in (first, *complete[1:]):
                self.enter(line, False)
        if tail:
            self.insert_text_at_cursor(tail)

    async def action_submit(self) -> None:
        """Take the line out and hand it over now, so keys already on their way start a
        fresh one (and, after a write that may ask, are held)."""
        line = self.value
        self.value = ""
        self._position = None
        self._draft = ""
        if self.enter(line, True):
            self.hold()  # the keys after this Enter, until the line asked or ended

    def action_cursor_right(self, select: bool = False) -> None:
        from ..present.completion import hint

        needs = hint(self.value)
        if self.cursor_at_end and needs and input_suggestion(self) == self.value + needs:
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
        from ..present.completion import common_prefix, complete

        text = self.value[: self.cursor_position]
        candidates = complete(text, self._seen(), self.targets, cell=self.cell)
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
        """Up recalls the line at once; the console settles it by its result (a refused
        line is never suggested nor written)."""
        self.history.enter(line)


def dropped_text(count: int) -> str:
    """What the console says of the keys typed ahead of a question, and dropped."""
    keys_were = (
        "1 key typed ahead of the question was"
        if count == 1
        else f"{count} keys typed ahead of the question were"
    )
    return f"{keys_were} ignored: nothing typed before a question answers it"
