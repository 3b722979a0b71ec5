"""Thin prompt-toolkit adapters over the shared, pure completion and history code."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence

from prompt_toolkit.auto_suggest import AutoSuggest, Suggestion
from prompt_toolkit.buffer import Buffer
from prompt_toolkit.completion import CompleteEvent, Completer, Completion
from prompt_toolkit.document import Document
from prompt_toolkit.formatted_text import FormattedText, StyleAndTextTuples
from prompt_toolkit.history import History as PromptHistory
from prompt_toolkit.layout.processors import (
    Processor,
    Transformation,
    TransformationInput,
)
from prompt_toolkit.lexers import Lexer
from prompt_toolkit.styles import Style

from ..commands.line import MAX_LINE
from ..engine import ConfirmWrite, Status
from ..present.cell_status import Badge, cell_status_text
from ..present.completion import complete, hint
from ..present.history import History
from ..present.render import too_long_text
from ..present.status import ink_on, label_text, profile_colour, target_label
from ..present.tokens import tokenize
from ..protocol.text import terminal_safe

STYLE = Style.from_dict(
    {
        "command": "bold ansicyan",
        "type": "ansiyellow",
        "index": "ansigreen",
        "value": "",
        "raw": "ansimagenta",
        "error": "ansired",
        "hint": "#808080",
        "auto-suggestion": "#808080",
        "bottom-toolbar": "noreverse bg:#303030 #d0d0d0",
        "toolbar.readonly": "bold bg:ansiblue ansiwhite",
        "toolbar.confirm": "bold bg:ansimagenta ansiwhite",
        "toolbar.open": "",
        "toolbar.paused": "bold bg:ansiyellow ansiblack",
        "confirm": "bold",
        "confirm.value": "bold ansiyellow",
        "toolbar.hint": "italic bg:#303030 #ffffaf",
        "prompt.sim": "bold ansiyellow",
        "prompt.live": "bold ansired",
        "prompt.off": "ansibrightblack",
    }
)


def label_fragment_style(colour: str | None) -> str:
    """A profile's label block: its colour behind, ink that reads on it; reversed for a
    profile without a colour or with one nobody knows."""
    parsed = profile_colour(colour)
    if parsed is None:
        return "bold reverse"
    red, green, blue = parsed.get_truecolor()
    ink = "#000000" if ink_on(parsed) == "black" else "#ffffff"
    return f"bold bg:#{red:02x}{green:02x}{blue:02x} {ink}"


def prompt_fragments(
    status: Status | None, lost: bool, current: str | None = None
) -> FormattedText:
    """``sim> ``, ``HOST:PORT> ``, `` Cell 3 — welding > `` (a profile's label in its
    colour) or ``not connected> ``; in a cell, the current target's name: ``cell3 › ``."""
    if current is not None:
        style = (
            label_fragment_style(status.colour)
            if status is not None and status.colour
            else "class:prompt.live"
        )
        return FormattedText([(style, terminal_safe(current)), ("", " › ")])
    if status is None or not status.has_session or (lost and status.connection != "connected"):
        return FormattedText([("class:prompt.off", "not connected"), ("", "> ")])
    label = target_label(status)
    if label is not None:
        return FormattedText([(label_fragment_style(status.colour), f" {label} "), ("", "> ")])
    if status.is_simulator:
        return FormattedText([("class:prompt.sim", "sim"), ("", "> ")])
    return FormattedText([("class:prompt.live", f"{status.host}:{status.port}"), ("", "> ")])


def toolbar_fragments(status: Status) -> FormattedText:
    """The toolbar's target: the profile's label in its colour, the target, what it
    lets be written (``READ-ONLY``, ``CONFIRM WRITES``, ``writes open``),
    ``POLLING PAUSED`` after ``pause``, and ``via agent``, as the console's status line
    says it."""
    parts: StyleAndTextTuples = []
    label = target_label(status)
    if label is not None:
        parts.append((label_fragment_style(status.colour), f" {label} "))
    parts.append(("", f" {terminal_safe(status.target)} "))
    if status.read_only:
        parts.append(("class:toolbar.readonly", " READ-ONLY "))
    elif status.writes == "confirm":
        parts.append(("class:toolbar.confirm", " CONFIRM WRITES "))
    elif status.writes == "open":
        parts.append(("class:toolbar.open", " writes open "))
    if status.paused:
        parts.append(("class:toolbar.paused", " POLLING PAUSED "))
    if status.via:  # the session is the agent's, shared with its other clients
        parts.append(("", f" {terminal_safe(status.via)} "))
    return FormattedText(parts)


def cell_toolbar_fragments(
    names: Sequence[str], statuses: Mapping[str, Status], current: str
) -> list[tuple[str, str]]:
    """A cell's toolbar: one badge per target (the console's, as text), the current one
    marked, so one controller down never looks like the cell down."""
    badges = [Badge(name, statuses.get(name), current=name == current) for name in names]
    return [("class:toolbar", f" {cell_status_text(badges).plain} ")]


def confirm_message(
    question: ConfirmWrite, member: str | None = None, ready: bool = True
) -> FormattedText:
    """``Write I10: 14 → 15 on Cell 3 — welding? [y/N] `` (default No); in a cell, led
    by the target's name: ``Write I10: 14 → 15 on cell3 (Cell 3 — welding)?``. Until
    ``ready`` (a yes typed now would be asked again), ``…`` stands where ``[y/N]`` will."""
    before = question.before
    where = label_text(question.label) if question.label else terminal_safe(question.target)
    if member is not None:
        where = f"{terminal_safe(member)} ({where})"
    return FormattedText(
        [
            ("class:confirm", f"Write {terminal_safe(question.var)}: "),
            (
                "class:confirm.value" if before is not None else "italic",
                terminal_safe(before) if before is not None else "value now unknown",
            ),
            ("class:confirm", " → "),
            ("class:confirm.value", terminal_safe(question.after)),
            ("class:confirm", f" on {where}? "),
            ("bold", "[y/N] " if ready else "… "),
        ]
    )


class RacCompleter(Completer):
    """Candidates from :func:`complete`, each with its one line of help."""

    def __init__(
        self,
        seen: Callable[[], Iterable[tuple[str, int]]],
        targets: Iterable[tuple[str, str]] = (),
        cell: Iterable[tuple[str, str]] = (),
    ) -> None:
        self._seen = seen
        self._targets = tuple(targets)  # the profiles connect completes to
        self._cell = tuple(cell)  # a cell's open targets: use NAME, @NAME

    def get_completions(
        self, document: Document, complete_event: CompleteEvent
    ) -> Iterator[Completion]:
        text = document.text_before_cursor
        for candidate in complete(text, self._seen(), self._targets, cell=self._cell):
            yield Completion(
                candidate.text, start_position=-candidate.start, display_meta=candidate.help
            )


class RacLexer(Lexer):
    """Colours each token: command, type, index, value, raw RAC string."""

    def lex_document(self, document: Document) -> Callable[[int], StyleAndTextTuples]:
        lines = document.lines

        def line(number: int) -> StyleAndTextTuples:
            if number >= len(lines):
                return []
            return [
                (f"class:{kind}" if kind != "space" else "", text)
                for kind, text in tokenize(lines[number])
            ]

        return line


class HintProcessor(Processor):
    """Grey text after the cursor saying what the command still needs; never inserted."""

    def apply_transformation(self, ti: TransformationInput) -> Transformation:
        buffer = ti.buffer_control.buffer
        document = ti.document
        at_end = document.is_cursor_at_the_end and ti.lineno == document.line_count - 1
        if not at_end or buffer.suggestion:
            return Transformation(ti.fragments)
        needs = hint(document.text)
        if not needs:
            return Transformation(ti.fragments)
        return Transformation([*ti.fragments, ("class:hint", needs)])


class SharedHistory(PromptHistory):
    """prompt-toolkit's view of the history file the console uses too: the file's
    lines, then what was entered here (Up recalls a refused line too, to be fixed)."""

    def __init__(self, history: History) -> None:
        self._shared = history
        super().__init__()

    def load_history_strings(self) -> Iterable[str]:
        return reversed(self._shared.entries)

    def store_string(self, string: str) -> None:
        """Nothing goes to the file here: the REPL enters each line it runs and settles
        it by its result (:meth:`History.settle`), so a refused one is never kept."""


class SharedSuggest(AutoSuggest):
    """The grey suggestion from the shared history, as the console makes it: never a
    line refused in this session."""

    def __init__(self, history: History) -> None:
        self._shared = history

    def get_suggestion(self, buffer: Buffer, document: Document) -> Suggestion | None:
        text = document.text.rsplit("\n", 1)[-1]
        line = self._shared.suggest(text)
        return Suggestion(line[len(text) :]) if line is not None else None


class LineCap:
    """The prompt's line holds at most :data:`MAX_LINE` characters, as the console's
    does (a prompt-toolkit buffer has no bound): what is typed or pasted past that is
    not taken, and ``say`` is told once while the line stays full."""

    def __init__(self, say: Callable[[str], object]) -> None:
        self._say = say
        self._said = False

    def attach(self, buffer: Buffer) -> None:
        buffer.on_text_insert += self.inserted
        buffer.on_text_changed += self.changed

    def inserted(self, buffer: Buffer) -> None:
        """Text was just inserted before the cursor: what is past the room goes."""
        text, cursor = buffer.text, buffer.cursor_position
        over = len(text) - MAX_LINE
        if over <= 0:
            return
        start = max(0, cursor - over)
        kept = text[:start] + text[cursor:]
        buffer.set_document(Document(kept[:MAX_LINE], min(start, MAX_LINE)), bypass_readonly=True)
        if not self._said:
            self._said = True
            self._say(too_long_text(None))

    def changed(self, buffer: Buffer) -> None:
        if len(buffer.text) < MAX_LINE:
            self._said = False
