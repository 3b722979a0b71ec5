"""What fits at the cursor: completion candidates and argument hints.

Pure functions of the text before the cursor, so the console and the REPL show
the same candidates and hints, and tests need no terminal.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

from ..protocol import KINDS
from .language import is_raw_line
from .registry import COMMANDS, Completes

_TYPE_HELP = {code: kind.title for code, kind in KINDS.items()}


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
) -> list[Candidate]:
    """Candidates for the word at the end of ``text``.

    ``seen`` holds (TYPE, index) pairs already used or watched, offered as indices;
    ``targets`` the config file's profiles (name, label or host), offered after connect.
    """
    if is_raw_line(text):
        return []
    done, partial = _tokens(text)
    done = _split_var(done)
    low = partial.lower()
    start = len(partial)

    def matching(options: Iterable[tuple[str, str]]) -> list[Candidate]:
        return [Candidate(o, h, start) for o, h in options if o.lower().startswith(low)]

    if not done:
        return matching((name, spec.summary) for name, spec in COMMANDS.items())
    command = done[0].lower()
    spec = COMMANDS.get(command)
    completes = spec.completes if spec is not None else Completes.NOTHING
    if completes is Completes.COMMAND and len(done) == 1:
        return matching((name, spec.summary) for name, spec in COMMANDS.items())
    if completes is Completes.TARGET and len(done) == 1:
        return matching([("sim", "the built-in simulator"), *targets])
    if completes is Completes.ON_OFF and len(done) == 1:
        return matching([("on", "echo every frame"), ("off", "stop echoing frames")])
    if completes is not Completes.VARIABLE:
        return []
    if len(done) == 1:
        options = [(code, _TYPE_HELP[code]) for code in KINDS]
        if command == "unwatch":
            options.append(("all", "every watched variable"))
        return matching(options)
    kind = KINDS.get(done[1].upper())
    if kind is None:
        return []
    if len(done) == 2:
        indices = sorted({i for code, i in seen if code == kind.code})
        return matching((str(i), f"{kind.code}{i}") for i in indices)
    if command == "put" and len(done) == 3 and kind.code == "IO":
        return matching([("on", "set the bit (sends 11,-1)"), ("off", "clear it (sends 11,0)")])
    if command == "wait" and len(done) == 3:
        options = [("changes", "until the value differs from the first read")]
        if kind.code == "IO":
            options[:0] = [("on", "until the bit is set"), ("off", "until it is clear")]
        options += [("==", "until it equals VALUE"), ("!=", "until it differs from VALUE")]
        if kind.code in ("I", "F", "D"):
            options += [(op, f"until it is {op} NUMBER") for op in ("<", "<=", ">", ">=")]
        return matching(options)
    return []


#: A candidate list this long or shorter is listed whole (the 9 types, the 7 conditions
#: of a ``wait`` on a number): a cut short list hides the very choice asked for. A longer
#: one (the 19 commands) is cut: it would push the rest of the screen away.
WHOLE_LIST = 12


def shown_candidates(candidates: list[Candidate]) -> tuple[list[Candidate], int]:
    """The candidates to list, and how many are left out: a list of up to
    :data:`WHOLE_LIST` whole; a longer one its first ``WHOLE_LIST - 1``, so the list
    with its "… and N more" line still takes ``WHOLE_LIST`` lines."""
    if len(candidates) <= WHOLE_LIST:
        return candidates, 0
    shown = candidates[: WHOLE_LIST - 1]
    return shown, len(candidates) - len(shown)


def hint(text: str) -> str:
    """Grey text showing what the command still needs, redis-cli style; '' if nothing."""
    if not text or is_raw_line(text):
        return ""
    done, partial = _tokens(text)
    if partial or not done:
        return ""
    done = _split_var(done)
    command = done[0].lower()
    spec = COMMANDS.get(command)
    if spec is None:
        return ""
    needs = spec.arguments.split()
    if spec.takes_variable and len(done) >= 2:
        kind = KINDS.get(done[1].upper())
        if kind is None:
            return ""
        if command == "put":
            needs = ["TYPE", "INDEX", *kind.value_hint.split()]
            if kind.code == "S":
                needs = ["TYPE", "INDEX", "TEXT"]
    if command == "latency":
        return _latency_hint(done[1:])
    if command == "wait" and len(done) >= 3:
        return _wait_hint([word.lower() for word in done[3:]])
    if command == "watch" and any(word.lower() == "every" for word in done[3:]):
        return "SECONDS" if done[-1].lower() == "every" else ""
    remaining = needs[len(done) - 1 :]
    return " ".join(remaining)


def _latency_hint(words: list[str]) -> str:
    """``latency [COUNT] [TYPE INDEX]``: a count is a number, so after one (or none) the
    variable follows."""
    if not words:
        return "[COUNT] [TYPE INDEX]"
    if words[0].isascii() and words[0].isdigit():
        words = words[1:]
        if not words:
            return "[TYPE INDEX]"
    return {1: "INDEX"}.get(len(_split_var(["latency", *words])) - 1, "")


_OPERATORS = ("==", "=", "!=", "<", "<=", ">", ">=")


def _wait_hint(words: list[str]) -> str:
    """What a ``wait`` still needs after its variable."""
    if not words:
        return "CONDITION [within SECONDS]"
    if words[-1] == "within":
        return "SECONDS"
    if "within" in words:
        return ""
    if words == [words[0]] and words[0] in _OPERATORS:
        return "VALUE [within SECONDS]"
    return "[within SECONDS]"


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
