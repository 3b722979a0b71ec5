"""The sample sessions of README.md and docs/*.md, found by their marks, and the rules
by which a sample is compared with what the program really printed.

A fenced block is a checked sample when the line before its fence is a mark::

    <!-- sample: repl -->                 a REPL session on the built-in simulator:
                                          $ rac-console repl, then "sim> LINE" typed
                                          and what the REPL printed after each
    <!-- sample: cli -->                  "$ COMMAND" lines (bash, rac-console in it) each
                                          followed by what it printed; "rac-console: "
                                          lines are its stderr, the others its stdout;
                                          "$ echo $?" shows the previous one's status
    <!-- sample: console: put I 10 5 -->  what the console's results pane shows for
                                          that line typed
    <!-- sample: python -->               a Python script (the library): it runs with
                                          the built-in simulator, exits 0 and says
                                          nothing on stderr; what it checks, it asserts

and, after ``;``, ``numbers vary`` (the simulator's moving values: every number is
compared as a number, not by its value) or ``5999 is a free port`` (the sample's port
5999 is one nothing listens on: the test gives it a free one). A sample that cannot be
checked here says why: ``<!-- sample not checked: needs a controller -->``; a block that
starts with ``$ `` or ``sim> `` and carries neither mark is a sample nobody checks, which
the test refuses, as is a ```python block with no mark. Marks are HTML comments: GitHub
shows none of them.

Round-trip times, clock times, the simulator's port and a watch row's age vary from run
to run: they are compared normalised (``0.22 ms`` as ``<ms> ms``); ``...`` in a sample's
line stands for any text (an elided JSON object's other keys).
"""

from __future__ import annotations

import difflib
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

ROOT = Path(__file__).resolve().parent.parent.parent
#: The pages whose samples are checked against the program.
PAGES = ("README.md", "docs/cli.md", "docs/repl.md")
#: The pages whose Python samples (the library's) are run.
PYTHON_PAGES = ("README.md", "docs/library.md")

Kind = Literal["repl", "cli", "console", "python"]
_KINDS: dict[str, Kind] = {"repl": "repl", "cli": "cli", "console": "console", "python": "python"}

_FENCE = re.compile(r"^(```|~~~)")
_MARK = re.compile(r"^<!--\s*sample(?P<not>\s+not checked)?\s*:\s*(?P<body>.*?)\s*-->\s*$")
_FREE_PORT = re.compile(r"^(\d+) is a free port$")


@dataclass(frozen=True)
class Sample:
    """One checked sample: where it is, how it is run, and its lines."""

    page: str
    line: int  # the fence's line, from 1
    kind: Kind
    lines: tuple[str, ...]
    typed: str | None = None  # console: the line typed
    numbers_vary: bool = False
    free_ports: tuple[int, ...] = field(default=())

    @property
    def name(self) -> str:
        return f"{self.page}:{self.line}"


@dataclass(frozen=True)
class Found:
    """What a page holds: its checked samples, the unchecked ones with why, and the
    lines of blocks that look like samples but carry no mark."""

    samples: list[Sample]
    unchecked: list[tuple[int, str]]
    unmarked: list[int]


def read_page(page: str, text: str | None = None) -> Found:
    """The samples of ``page`` (a path under the repository), or of ``text`` as if it
    were that page. ValueError for a mark that cannot be read."""
    if text is None:
        text = (ROOT / page).read_text(encoding="utf-8")
    lines = text.splitlines()
    found = Found([], [], [])
    at = 0
    while at < len(lines):
        fence = _FENCE.match(lines[at])
        if fence is None:
            at += 1
            continue
        end = next(
            (n for n in range(at + 1, len(lines)) if lines[n].startswith(fence.group(1))),
            len(lines),
        )
        block = tuple(lines[at + 1 : end])
        mark = _MARK.match(lines[at - 1]) if at > 0 else None
        if mark is None:
            python = lines[at][3:].strip().lower() in ("python", "py")
            if python or (block and block[0].startswith(("$ ", "sim> "))):
                found.unmarked.append(at + 1)
        elif mark.group("not"):
            found.unchecked.append((at + 1, mark.group("body")))
        else:
            found.samples.append(_sample(page, at + 1, mark.group("body"), block))
        at = end + 1
    return found


def _sample(page: str, line: int, body: str, block: tuple[str, ...]) -> Sample:
    what, *options = (part.strip() for part in body.split(";"))
    word, _, typed = (part.strip() for part in what.partition(":"))
    kind = _KINDS.get(word)
    if kind is None or (kind == "console") != bool(typed):
        raise ValueError(
            f"{page}:{line}: a sample is repl, cli or console: LINE (or python), not {what!r}"
        )
    numbers_vary, ports = False, []
    for option in options:
        if option == "numbers vary":
            numbers_vary = True
        elif (port := _FREE_PORT.match(option)) is not None:
            ports.append(int(port.group(1)))
        else:
            raise ValueError(f"{page}:{line}: no such option of a sample: {option!r}")
    return Sample(page, line, kind, block, typed or None, numbers_vary, tuple(ports))


# ------------------------------------------------------------------ comparing

_ISO_TIME = re.compile(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\.\d{3}(?:[+-]\d{2}:\d{2}|Z)")
_CLOCK = re.compile(r"\b\d{2}:\d{2}:\d{2}\.\d{3}\b")
_MS = re.compile(r"\b\d+(?:\.\d+)? ms\b")
_RTT = re.compile(r'"rtt_ms": \d+(?:\.\d+)?')
_SIM_PORT = re.compile(r"\b127\.0\.0\.1:\d+")
_AGE = re.compile(r"(?<= )<?\d+[smh](?= |$)")
_NUMBER = re.compile(r"(?<![A-Za-z\d.])-?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?(?![\d.])")


def normalised(line: str, numbers_vary: bool = False) -> str:
    """``line`` with what varies from run to run replaced by a placeholder."""
    line = _ISO_TIME.sub("<time>", line)
    line = _CLOCK.sub("<clock>", line)
    line = _MS.sub("<ms> ms", line)
    line = _RTT.sub('"rtt_ms": <ms>', line)
    line = _SIM_PORT.sub("127.0.0.1:<port>", line)
    line = _AGE.sub("<age>", line)
    if numbers_vary:
        line = _NUMBER.sub("<n>", line)
    return line.rstrip()


def _fits(expected: str, actual: str) -> bool:
    if "..." not in expected:
        return expected == actual
    pattern = ".*".join(re.escape(part) for part in expected.split("..."))
    return re.fullmatch(pattern, actual) is not None


def agrees(expected: list[str], actual: list[str], numbers_vary: bool = False) -> bool:
    """Whether the lines a sample shows are the lines printed, once normalised."""
    shown = [normalised(line, numbers_vary) for line in expected]
    printed = [normalised(line, numbers_vary) for line in actual]
    return len(shown) == len(printed) and all(map(_fits, shown, printed))


def difference(what: str, expected: list[str], actual: list[str], numbers_vary: bool) -> str:
    """Why a sample disagrees: the sample against the program, normalised, as a diff."""
    shown = [normalised(line, numbers_vary) for line in expected]
    printed = [normalised(line, numbers_vary) for line in actual]
    diff = difflib.unified_diff(shown, printed, "the sample", "the program", lineterm="")
    return f"{what}: the sample is not what the program prints\n" + "\n".join(diff)


def run_python(text: str, folder: Path, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """``text`` run as a script (a python sample, or a test's own) in a fresh interpreter,
    in ``folder`` with ``env`` (the test's private HOME): what it printed, and its status."""
    script = folder / "script.py"
    script.write_text(text, encoding="utf-8")
    return subprocess.run(
        [sys.executable, str(script)],
        capture_output=True,
        text=True,
        cwd=folder,
        env=env,
        timeout=120,
    )
