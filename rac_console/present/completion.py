"""What fits at the cursor: completion candidates and argument hints.

Pure functions of the text before the cursor, so the console and the REPL show
the same candidates and hints, and tests need no terminal. What a command takes is
its registry entry's to say (:mod:`rac_console.engine.commands.registry`); nothing here names
a command.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from rich.text import Text

from ..commands.language import is_raw_line
from ..engine.commands.builtin import BUILTIN
from ..engine.commands.registry import Registry, Sources
from ..protocol import KINDS


@dataclass(frozen=True)
class Candidate:
    """A completion: ``text`` replaces the word being typed (``start`` chars back)."""

    text: str
    help: str
    start: int


def _tokens(text: str) -> tuple[list[str], str]:
    """Finished words before the cursor, and the word being typed ('' after a space)."""
    words = text.split()
    if text and not text[-1].isspace() and words:
        return words[:-1], words[-1]
    return words, ""


def _split_var(words: list[str]) -> list[str]:
    """Treat ``P10`` and ``P[10]`` like ``P 10`` so the position counts stay simple."""
    if len(words) >= 2:
        match = re.fullmatch(r"([A-Za-z]+)\[?(\d+)\]?", words[1], re.ASCII)
        if match and match.group(1).upper() in KINDS:
            return [words[0], match.group(1), match.group(2), *words[2:]]
    return words


def complete(
    text: str,
    seen: Iterable[tuple[str, int]] = (),
    targets: Iterable[tuple[str, str]] = (),
    registry: Registry = BUILTIN,
    cell: Sequence[tuple[str, str]] = (),
) -> list[Candidate]:
    """Candidates for the word at the end of ``text``: a command name, or what the
    command's entry offers for the argument being typed.

    ``seen`` holds (TYPE, index) pairs already used or watched, offered as indices;
    ``targets`` the config file's profiles (name, label or host), offered after connect;
    ``cell`` a cell's open targets (name, label), offered after ``use`` and as ``@NAME``
    at the start of a line (the line after it completes as any other).
    """
    if cell and text.lstrip().startswith("@"):
        head = text.lstrip()
        name, space, rest = head.partition(" ")
        if not space:
            return [Candidate(f"@{n}", h, len(name)) for n, h in cell if f"@{n}".startswith(name)]
        return complete(rest.lstrip(), seen, targets, registry, cell)
    if is_raw_line(text):
        return []
    done, partial = _tokens(text)
    done = _split_var(done)
    low = partial.lower()
    start = len(partial)
    names = [(spec.name, spec.summary) for spec in registry]
    if not done:
        options: Sequence[tuple[str, str]] = names
    else:
        spec = registry.get(done[0].lower())
        if spec is None:
            return []
        options = spec.complete(done[1:], Sources(seen, targets, names, cell))
    return [Candidate(o, h, start) for o, h in options if o.lower().startswith(low)]


#: A candidate list this long or shorter is listed whole (the 9 types, the 7 conditions
#: of a ``wait`` on a number): a cut short list hides the very choice asked for. A longer
#: one (the 19 commands) is cut: it would cover the rest of the screen. A front end with
#: less room than this lists what fits (see ``room`` below).
WHOLE_LIST = 12


def shown_candidates(
    candidates: list[Candidate], room: int = WHOLE_LIST, first: int = 0
) -> tuple[list[Candidate], int]:
    """The candidates to list in ``room`` lines, from the ``first``, and how many are
    left out: a list that fits is shown whole; a longer one a page of ``room - 1``, so
    that with its "… and N more" line it still takes ``room`` lines."""
    if len(candidates) <= room:
        return candidates, 0
    shown = candidates[first : first + max(1, room - 1)]
    return shown, len(candidates) - len(shown)


def next_page(count: int, room: int, first: int) -> int:
    """The first candidate of the page after the one from ``first`` (Tab again), back
    to the start after the last: every candidate is reached in turn."""
    if count <= room:
        return 0
    following = first + max(1, room - 1)
    return following if following < count else 0


def completions_text(
    candidates: list[Candidate], room: int = WHOLE_LIST, first: int = 0, width: int = 0
) -> Text:
    """The list over the command line: each candidate and what it means, aligned, a
    line each (cut at ``width`` with an ellipsis when given, never wrapped: the list
    takes as many lines as it counts), and how many more when it is cut to ``room``."""
    shown, more = shown_candidates(candidates, room, first)
    column = max(len(c.text) for c in shown)
    lines: list[Text] = []
    for candidate in shown:
        line = Text(f"{candidate.text:<{column}}", style="bold")
        line.append(f"  {candidate.help}", style="dim")
        lines.append(line)
    if more:
        tail = f"… and {more} more: Tab again, or type to narrow"
        lines.append(Text(tail, style="italic"))
    if width > 0:
        for line in lines:
            line.truncate(width, overflow="ellipsis")
    return Text("\n", end="").join(lines)


def hint(text: str, registry: Registry = BUILTIN) -> str:
    """Grey text showing what the command still needs, redis-cli style; '' if nothing."""
    if not text or is_raw_line(text):
        return ""
    done, partial = _tokens(text)
    if partial or not done:
        return ""
    done = _split_var(done)
    spec = registry.get(done[0].lower())
    if spec is None:
        return ""
    args = done[1:]
    if spec.takes_variable and args and args[0].upper() not in KINDS:
        return ""
    return spec.hint_for(args)


def common_prefix(candidates: list[Candidate]) -> str:
    """The longest text every candidate starts with (case-insensitively)."""
    if not candidates:
        return ""
    first = candidates[0].text
    length = len(first)
    for candidate in candidates[1:]:
        length = min(length, len(candidate.text))
        for i in range(length):
            if candidate.text[i].lower() != first[i].lower():
                length = i
                break
    return first[:length]
