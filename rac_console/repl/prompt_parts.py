"""Thin prompt-toolkit adapters over the shared, pure completion and history code."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator

from prompt_toolkit.completion import CompleteEvent, Completer, Completion
from prompt_toolkit.document import Document
from prompt_toolkit.formatted_text import StyleAndTextTuples
from prompt_toolkit.history import History as PromptHistory
from prompt_toolkit.layout.processors import (
    Processor,
    Transformation,
    TransformationInput,
)
from prompt_toolkit.lexers import Lexer
from prompt_toolkit.styles import Style

from ..commands.completion import complete, hint
from ..commands.tokens import tokenize
from ..present.history import History

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
        "toolbar.hint": "italic bg:#303030 #ffffaf",
        "prompt.sim": "bold ansiyellow",
        "prompt.live": "bold ansired",
        "prompt.off": "ansibrightblack",
    }
)


class RacCompleter(Completer):
    """Candidates from :func:`complete`, each with its one line of help."""

    def __init__(self, seen: Callable[[], Iterable[tuple[str, int]]]) -> None:
        self._seen = seen

    def get_completions(
        self, document: Document, complete_event: CompleteEvent
    ) -> Iterator[Completion]:
        for candidate in complete(document.text_before_cursor, self._seen()):
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
    """prompt-toolkit's view of the history file the console uses too."""

    def __init__(self, history: History) -> None:
        self._shared = history
        super().__init__()

    def load_history_strings(self) -> Iterable[str]:
        return reversed(self._shared.entries)

    def store_string(self, string: str) -> None:
        self._shared.append(string)
