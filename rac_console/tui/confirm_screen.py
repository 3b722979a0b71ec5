"""The question a write on a ``confirm`` target asks: old → new, ``[y/N]``, default No.

Muscle memory must not answer it (k9s users "blow right through" confirm dialogs): a key
that arrived before the question was painted, or within :data:`GUARD_SECONDS` after, is
ignored, and so is every key that follows the one before by less than that (a burst typed
ahead stays ignored until it pauses): a typed-ahead Enter or y answers nothing. Then
Enter, n and Esc answer No, only y (or a click on Yes) answers Yes; Esc answers No at
any time. Nothing here can be focused, so no Enter presses a button.

What the keys line says follows the guard: ``… wait`` while keys are ignored, ``[y/N]``
only once a y would count (and the Yes button is disabled until then), so whoever
answers, a person or a test, sees when an answer is taken.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.text import Text
from textual import events, on
from textual.app import App, ComposeResult
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Static

from ..engine import CONFIRM_GUARD_SECONDS, ConfirmWrite
from ..present.status import label_text
from ..protocol.text import terminal_safe
from .borders import border_colour
from .command_line import CommandLine
from .compat import event_clock  # the clock of an event's ``time``

if TYPE_CHECKING:
    from .lines import Lines
    from .members import MemberState

#: Keys in the first this many seconds of the question (and any typed before it) are
#: ignored; Esc still answers No.
GUARD_SECONDS = CONFIRM_GUARD_SECONDS  # as the REPL's (tests lengthen it here)

#: How often the keys line looks whether the guard time is over.
READY_TICK = 0.05

#: What the keys line shows while keys are ignored, and once a y counts.
WAITING_KEYS = Text.assemble(("… ", "bold"), "wait: keys now are ignored · Esc: no")
READY_KEYS = Text.assemble(("[y/N] ", "bold"), "y writes · Enter, n or Esc: no")


def question_text(question: ConfirmWrite) -> Text:
    """``Write I10: 14 → 15`` (``value now unknown`` when it could not be read)."""
    before = terminal_safe(question.before) if question.before is not None else None
    text = Text("Write ")
    text.append(f"{terminal_safe(question.var)}: ", style="bold")
    if before is None:
        text.append("value now unknown", style="italic")
    else:
        text.append(before, style="bold")
    text.append(" → ")
    text.append(terminal_safe(question.after), style="bold")
    return text


class ConfirmWriteScreen(ModalScreen[bool]):
    """Dismissed with True only for y (or Yes clicked) once the guard time is over."""

    AUTO_FOCUS = None  # nothing here takes the focus: keys come to the screen
    CSS_PATH = "confirm_screen.tcss"

    def __init__(
        self, question: ConfirmWrite, colour: str | None = None, member: str | None = None
    ) -> None:
        """``member``: in a cell, the target's name (said first: which robot moves)."""
        super().__init__()
        self.question = question
        self.colour = colour
        self.member = member
        self.ignored = 0  # keys ignored: typed ahead, or within the guard time
        self._ready_at = float("inf")  # event_clock() from when keys answer
        self._ready_shown = False  # the keys line says [y/N]
        self._answered = False

    @property
    def shown(self) -> bool:
        """True once the question is on screen (its guard time runs)."""
        return self._ready_at != float("inf")

    @property
    def accepting(self) -> bool:
        """True once keys answer the question."""
        return event_clock() >= self._ready_at

    def compose(self) -> ComposeResult:
        question = self.question
        where = label_text(question.label) if question.label else terminal_safe(question.target)
        if self.member is not None:
            where = f"{terminal_safe(self.member)} · {where}"
        with Vertical(id="confirm-box") as box:
            box.border_title = Text(f" {where} ")
            if question.label:
                yield Static(Text(terminal_safe(question.target), style="dim"))
            yield Static(question_text(question), id="confirm-question")
            yield Static(Text(terminal_safe(question.request), style="dim"), id="confirm-request")
            yield Static(WAITING_KEYS, id="confirm-keys")
            yield Static(
                Text(
                    f"keys typed ahead are ignored: y counts once this has been up "
                    f"{GUARD_SECONDS:g} s with no key pressed",
                    style="dim italic",
                ),
                id="confirm-guard",
            )
            with Horizontal(id="confirm-buttons"):
                for button in (
                    Button("No", id="confirm-no", variant="primary"),
                    Button("Yes, write", id="confirm-yes", variant="error"),
                ):
                    button.can_focus = False  # by mouse only: Enter must never press one
                    button.disabled = button.id == "confirm-yes"  # until a y counts
                    yield button

    def on_mount(self) -> None:
        colour = border_colour(self.colour)
        if colour is not None:
            box = self.query_one("#confirm-box")
            box.styles.border = ("heavy", colour)
        self.call_after_refresh(self._on_screen)

    def _on_screen(self) -> None:
        """Painted: the guard time starts now (not when it was made: building a screen
        takes a moment, while keys typed ahead still arrive)."""
        self._ready_at = event_clock() + GUARD_SECONDS
        self.set_interval(READY_TICK, self._show_readiness)  # a tick, not a one-shot

    def _show_readiness(self) -> None:
        """The keys line (and the Yes button) say whether a y would count now: ``[y/N]``
        is never shown while a key would still be ignored."""
        ready = self.accepting
        if ready != self._ready_shown:
            self._ready_shown = ready
            # A tick may come as the screen closes, its widgets gone: none to update then.
            for keys in self.query("#confirm-keys").results(Static):
                keys.update(READY_KEYS if ready else WAITING_KEYS)
            for button in self.query("#confirm-yes").results(Button):
                button.disabled = not ready

    def on_key(self, event: events.Key) -> None:
        event.stop()
        event.prevent_default()
        if event.key == "escape":
            self.answer(False)
        elif event.time < self._ready_at:
            # Typed ahead, or too soon to have read the question: ignored, and a burst
            # of keys goes on being one until it pauses (five keys outlast 0.4 s).
            self.ignored += 1
            self._ready_at = max(self._ready_at, event.time + GUARD_SECONDS)
            self._show_readiness()  # a key from before [y/N] showed: wait again
        elif event.key in ("y", "Y"):
            self.answer(True)
        elif event.key in ("enter", "n", "N"):
            self.answer(False)

    def answer(self, yes: bool) -> None:
        """Dismiss once (a key and a click in the same moment answer once)."""
        if not self._answered:
            self._answered = True
            self.dismiss(yes)

    @on(Button.Pressed)
    def clicked(self, event: Button.Pressed) -> None:
        event.stop()
        if event.button.id == "confirm-no":
            self.answer(False)
        elif self.accepting:
            self.answer(True)


def ask(
    app: App[int], question: ConfirmWrite, state: MemberState, named: str | None, lines: Lines
) -> None:
    """A write on a ``confirm`` target asks first: old → new, ``[y/N]``, default No;
    the engine polls on until the answer, then the focus is back where it was (a
    table row or a grid bit: the next Space toggles the next one). The keys typed
    after the write's Enter were typed ahead of the question: they answer nothing."""
    colour = state.status.colour if state.status is not None else state.colour
    held = question.seq == lines.held_seq
    if held:
        lines.command_line.post_message(CommandLine.Asked())

    def answered(yes: bool | None) -> None:
        lines.cell.answer_confirm(question.seq, bool(yes))
        if not yes:  # no write: the row's next Space need not wait for the refusal
            state.toggles.declined(question.seq)
        if held and lines.held_seq == question.seq:
            lines.command_line.post_message(CommandLine.Answered())

    app.push_screen(ConfirmWriteScreen(question, colour, named), answered)


def close_question(app: App[int], seq: int) -> None:
    """A write that ended (a cancel came before its answer) asks nothing any more."""
    screen = app.screen
    if isinstance(screen, ConfirmWriteScreen) and screen.question.seq == seq:
        screen.dismiss(False)
