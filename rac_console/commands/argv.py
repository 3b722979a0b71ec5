"""The words of a one-shot ``get``, ``put`` or ``send`` as the shell passed them.

The CLI used to join its arguments into one line and parse that again, which lost
what the shell had quoted and took options after a value for part of it. Here the
words stay words: options are told from operands wherever they stand (``--`` ends
the options), and the command is built from the operands themselves, so a string is
written exactly as given. Pure: no I/O, no asyncio, no UI toolkit.
"""

from __future__ import annotations

import difflib
import re
import shlex
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from ..protocol import VT, InputError, Variant, format_variant
from ..protocol.variables import encode_value
from .language import Exchange, Get, Put, Raw, VarRef, parse_var

_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|[+-]?0[xX][0-9a-fA-F]+"
_NUMBERS_RE = re.compile(rf"(?:{_NUMBER})(?:,(?:{_NUMBER}))*", re.ASCII)
_CONTROL_RE = re.compile(r"[\x00-\x1f\x7f]")

_USAGE = {
    "get": "get TYPE INDEX, e.g. get I 10, get P3 or get P[3]",
    "put": "put TYPE INDEX VALUE..., e.g. put I 10 123",
}


@dataclass(frozen=True)
class Option:
    """An option the command line knows: its long name and its value's name."""

    name: str  # the long spelling handed on to argparse: --host
    metavar: str | None  # None: a flag, which takes no value


Options = Mapping[str, Option]  # every spelling (-H, --host) to its option


@dataclass(frozen=True)
class SplitWords:
    """A command's words sorted into options and operands.

    ``options`` are argparse words with any value attached (``--host=h``), so a
    value that starts with a dash cannot be misread. ``operands`` are every other
    word, verbatim and in order, without the ``--`` that ended the options. When
    ``problem`` is set the words cannot be used (nothing may be built from them);
    the word at fault stays among the operands so the input can still be shown.
    """

    options: tuple[str, ...]
    operands: tuple[str, ...]
    problem: str | None = None


def looks_like_number(word: str) -> bool:
    """``-5``, ``-1e3``, ``.5``, ``-0x1F`` or ``-1,-2,3``: a value, never an option.

    Our own pattern, not argparse's (which takes ``-1e3`` for an option).
    """
    return _NUMBERS_RE.fullmatch(word) is not None


def looks_like_option(word: str) -> bool:
    return word.startswith("-") and word != "-" and not looks_like_number(word)


def find_command(words: Sequence[str], options: Options) -> int | None:
    """Where the command word is, reading the words before it as argparse does.

    Options before the command may be abbreviated (``--tim 3``) and may carry their
    value in the same word (``--host=h``, ``-Hh``). None when there is no command
    word, or a ``--`` comes first (argparse then has the last word).
    """
    at = 0
    while at < len(words):
        word = words[at]
        if word == "--":
            return None
        if not looks_like_option(word):
            return at
        option = _resolve(word, options, abbreviations=True)
        at += 2 if option and option.metavar and _attached(word) is None else 1
    return None


def split_words(
    command: str, words: Sequence[str], options: Options, before: Sequence[str] = ()
) -> SplitWords:
    """Sort the words after ``get``/``put``/``send`` into options and operands.

    Only whole option names count here, not abbreviations, which could turn a
    mistyped value into an option. Any other word that looks like an option is a
    problem that says how to write it as a value; ``before`` (the words before the
    command) only goes into that advice, so it can be pasted as it is.
    """
    walk = _Walk(words, options)
    if walk.problem is not None:
        return SplitWords(tuple(walk.options), tuple(walk.operands), walk.problem)
    if walk.stray is None:
        return SplitWords(tuple(walk.options), tuple(walk.operands))
    word = walk.operands[walk.stray]
    longs = sorted({o.name for o in options.values()} - {"--help"})
    close = difflib.get_close_matches(word.partition("=")[0], longs, n=1, cutoff=0.75)
    hint = f" (did you mean {close[0]}?)" if close else ""
    if command == "get":
        problem = (
            f"get has no option {word!r}{hint}: its options are {', '.join(longs)} "
            "(rac-console get --help)"
        )
    else:
        fixed = [
            "rac-console",
            *before,
            command,
            *walk.typed,
            *walk.operands[: walk.stray],
            "--",
            *walk.operands[walk.stray :],
        ]
        what = "to send it as text" if command == "send" else "to write it as the value"
        problem = f"{word!r} looks like an option{hint}; {what} put it after --: " + " ".join(
            shlex.quote(w) for w in fixed
        )
    return SplitWords(tuple(walk.options), tuple(walk.operands), problem)


class _Walk:
    """One pass over a command's words: options, operands and the first thing wrong."""

    def __init__(self, words: Sequence[str], options: Options) -> None:
        self.options: list[str] = []  # for argparse: --host=h
        self.typed: list[str] = []  # the same options as they were typed: -H h
        self.operands: list[str] = []
        self.stray: int | None = None  # the operand that looked like an unknown option
        self.problem: str | None = None  # a known option used wrongly
        at = 0
        while at < len(words):
            word = words[at]
            at += 1
            if word == "--":
                self.operands += words[at:]
                return
            option = _resolve(word, options) if looks_like_option(word) else None
            attached = _attached(word)
            if option is None:
                if looks_like_option(word) and self.stray is None:
                    self.stray = len(self.operands)
                self.operands.append(word)
            elif option.metavar is None:
                if attached is not None:
                    self._fail(f"{option.name} takes no value: write {option.name}")
                self.options.append(option.name)
                self.typed.append(word)
            elif attached is not None:
                self.options.append(f"{option.name}={attached}")
                self.typed.append(word)
            elif at < len(words) and words[at] != "--" and not looks_like_option(words[at]):
                self.options.append(f"{option.name}={words[at]}")
                self.typed += [word, words[at]]
                at += 1
            else:
                self._fail(f"{word} needs a value: {word} {option.metavar}")

    def _fail(self, problem: str) -> None:
        if self.problem is None and self.stray is None:
            self.problem = problem


def exchange_from_words(command: str, operands: Sequence[str]) -> Exchange:
    """The Get, Put or Raw the operands of ``command`` name; InputError when refused.

    A string value is the words themselves (one word exactly as given, several
    joined with single spaces): nothing is unquoted or stripped.
    """
    if command == "send":
        text = " ".join(operands)
        if not text:
            raise InputError("send needs the text to send: rac-console send GET:RC8:10:I:")
        return Raw.of(text)
    usage = _USAGE[command]
    var, used = _variable(operands, usage)
    rest = operands[used:]
    if command == "get":
        if rest:
            raise InputError(f"get takes only a variable, not {' '.join(rest)!r}: get {var}")
        return Get(var)
    if var.kind.code == "S":
        put = _string_put(var, rest)
    else:
        variant, value_text = encode_value(var.kind, " ".join(rest))
        put = Put.of(var, variant, value_text)
    return put  # Put.of refused a non-ASCII value or one longer than a frame


def input_line(command: str, operands: Sequence[str]) -> str:
    """What the user typed, for ``input`` in JSON: the words joined with spaces."""
    return " ".join([command, *operands])


def _variable(operands: Sequence[str], usage: str) -> tuple[VarRef, int]:
    """The variable the first operands name and how many words it took.

    ``P3``, ``P[3]`` and ``p[3]`` are one word, ``P 3`` two; the value starts after.
    """
    if not operands:
        raise InputError(f"missing variable: {usage}")
    first = operands[0]
    text = first if len(operands) == 1 else f"{first} {operands[1]}"
    var, rest = parse_var(text, usage)
    used = len(text) - len(rest)
    if used <= len(first):
        if first[used:].strip():
            raise InputError(f"{first!r} is not a variable: {usage}")
        return var, 1
    if rest:
        raise InputError(f"index must be a whole number, got {operands[1]!r}: {usage}")
    return var, 2


def _string_put(var: VarRef, words: Sequence[str]) -> Put:
    """A PUT of an S variable with the words as its value, checked to be sendable."""
    if not words:
        raise InputError(f'{var} needs a value: write "" for an empty string')
    value = " ".join(words)  # one word stays exactly as the shell passed it
    if "\r" in value or "\n" in value:
        raise InputError("S cannot hold CR or LF: CR ends a RAC frame")
    control = _CONTROL_RE.search(value)
    if control:
        raise InputError(
            f"S cannot hold the control character {control.group()!r}: "
            "RAC strings are printable ASCII"
        )
    variant = Variant(VT.BSTR, value)
    return Put.of(var, variant, format_variant(variant))


def _attached(word: str) -> str | None:
    """The value an option word carries itself: ``--host=h``, ``-Hh`` and ``-H=h`` give h."""
    if word.startswith("--"):
        _, has_value, value = word.partition("=")
        return value if has_value else None
    return word[2:].removeprefix("=") if len(word) > 2 else None


def _resolve(word: str, options: Options, abbreviations: bool = False) -> Option | None:
    """The option a word names: whole, ``--name=value``, ``-Xvalue``, or abbreviated
    (``--tim``) where argparse would allow it."""
    name = word.partition("=")[0] if word.startswith("--") else word
    if name in options:
        return options[name]
    if not word.startswith("--"):
        short = options.get(word[:2])
        return short if short is not None and short.metavar is not None else None
    if abbreviations:
        matches = {options[o] for o in options if o.startswith("--") and o.startswith(name)}
        if len(matches) == 1:
            return matches.pop()
    return None
