"""The command line's refusals as one line that says what to write, not argparse's page.

argparse answers a mistyped command with its whole usage and ``invalid choice``, a
mistyped option with ``unrecognized arguments`` under the top-level usage, and an
option written before its command (``--count 3 watch I 1``), or one mistyped there
(``--hots 127.0.0.1 get``), with ``invalid choice`` naming the option's value.
The console and the REPL say ``did you mean get?``; so does this, in one line on stderr,
exit status 2, naming the ``--help`` to read.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

from ..protocol.text import close_match, terminal_safe

_INVALID_CHOICE = re.compile(r"argument COMMAND: invalid choice: '(.*?)' \(choose from")
_UNRECOGNIZED = re.compile(r"unrecognized arguments: (.*)")


class RacParser(argparse.ArgumentParser):
    """argparse, its errors said in one line (see the module)."""

    words: list[str]

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: Any = None
    ) -> tuple[argparse.Namespace, list[str]]:
        self.words = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def error(self, message: str) -> NoReturn:
        said = self._plain(message)
        command = self._command_name() or self._named_command()
        if command is not None and not said.startswith(command):
            said = f"{command}: {said}"
        where = f"rac-console {command}" if command else "rac-console"
        self.exit(2, f"rac-console: {terminal_safe(said)} ({where} --help says more)\n")

    # ------------------------------------------------------------ what to say

    def _plain(self, message: str) -> str:
        if (found := _INVALID_CHOICE.search(message)) is not None:
            return self._unknown_command(found.group(1))
        if (found := _UNRECOGNIZED.search(message)) is not None:
            return self._unknown_option(found.group(1).split()[0])
        return message.removeprefix("argument ")

    def _commands(self) -> dict[str, argparse.ArgumentParser]:
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                return dict(action.choices)
        return {}

    def _named_command(self) -> str | None:
        """The command word among the words (the top level's errors about its options)."""
        commands = self._commands()
        return next((w for w in getattr(self, "words", ()) if w in commands), None)

    def _command_name(self) -> str | None:
        """This parser's command (``watch``), None for the top level."""
        name = self.prog.removeprefix("rac-console").strip()
        return name or None

    def _unknown_command(self, word: str) -> str:
        commands = self._commands()
        before = self.words[: self.words.index(word)] if word in self.words else []
        misplaced = [w for w in before if w.startswith("-") and not self._knows(w)]
        named = next((w for w in self.words if w in commands), None)
        if misplaced and named is not None:
            owner = commands[named]
            if all(_option_of(owner, w) for w in misplaced):
                moved = _after_command(self.words, misplaced[0], named, owner)
                return f"{misplaced[0]} goes after {named}: rac-console {' '.join(moved)}"
        if misplaced:
            owners = sorted(n for n, p in commands.items() if _option_of(p, misplaced[0]))
            if owners:
                return f"{misplaced[0]} is an option of {', '.join(owners)}: write it after one"
            # An option no command knows (--hots 127.0.0.1 get): argparse took its value
            # for the command; the typo is the fault, said as after the command.
            return self._unknown_option(misplaced[0])
        guess = close_match(word, commands)
        shown = f"unknown command '{word}'"
        if guess is not None:
            return f"{shown}: did you mean {guess}?"
        return f"{shown}: the commands are {', '.join(commands)}"

    def _unknown_option(self, word: str) -> str:
        parser: argparse.ArgumentParser = self
        named = self._named_command()
        if named is not None:
            parser = self._commands()[named]
            if _option_of(parser, word) and self.words.index(word) < self.words.index(named):
                moved = _after_command(self.words, word, named, parser)
                return f"{word} goes after {named}: rac-console {' '.join(moved)}"
        options = [o for o in parser._option_string_actions if o.startswith("--")]
        guess = close_match(word.split("=", 1)[0], options)
        if guess is not None:
            return f"no option {word}: did you mean {guess}?"
        if not word.startswith("-"):
            return f"unexpected word '{word}'"
        return f"no option {word}"

    def _knows(self, word: str) -> bool:
        return _option_of(self, word)


def _option_of(parser: argparse.ArgumentParser, word: str) -> bool:
    return word.split("=", 1)[0] in parser._option_string_actions


def _after_command(
    words: list[str], option: str, command: str, owner: argparse.ArgumentParser
) -> list[str]:
    """``words`` with ``option`` (and its value, if it takes one) moved to the end."""
    at = words.index(option)
    taken = [option]
    flag = owner._option_string_actions[option.split("=", 1)[0]].nargs == 0
    if not flag and "=" not in option and at + 1 < len(words) and words[at + 1] != command:
        taken.append(words[at + 1])
    rest = words[:at] + words[at + len(taken) :]
    return rest + taken
