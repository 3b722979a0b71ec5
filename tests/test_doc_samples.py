"""The sample sessions in README.md, docs/cli.md and docs/repl.md are what the program
prints: each marked sample is run on the built-in simulator (the REPL through its pipe
driver, the console under Pilot, the CLI as a subprocess in bash) and compared line by
line, times and ports normalised. How samples are marked: tests/support/doc_samples.py.

docs/repl.md once showed ``IO20 ← ON  S_OK`` where the REPL prints ``IO20: OFF → ON
S_OK  read back ON ✓`` (issue 41): the last test here runs that old sample and sees it
refused.
"""

from __future__ import annotations

import asyncio
import re
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.present.render import make_console
from tests.support.doc_samples import (
    PAGES,
    Sample,
    agrees,
    difference,
    normalised,
    read_page,
)
from tests.support.drivers import Driver, Screen, make_app, results_text, type_line, until
from tests.support.servers import unused_port

#: How long a step waits for its lines before the next is typed. A sample that is
#: wrong waits this long once, then is judged on the whole output, which is complete
#: either way (the REPL and the console run lines in order).
SETTLE = 20.0
#: Wide enough for the samples' longest lines: the docs show them unwrapped.
WIDTH = 400

SAMPLES = [
    sample
    for page in PAGES
    for sample in read_page(page).samples
    if sample.kind != "python"  # the library's: tests/test_library_docs.py runs them
]


def test_every_sample_session_is_marked_checked_or_not() -> None:
    """A block that starts with ``$ `` or ``sim> `` says whether a test checks it."""
    unmarked = [f"{page}:{line}" for page in PAGES for line in read_page(page).unmarked]
    assert unmarked == [], "mark these as <!-- sample: ... --> or <!-- sample not checked: why -->"
    assert {s.kind for s in SAMPLES} == {"repl", "cli", "console"}


def test_what_varies_is_normalised_and_nothing_else() -> None:
    assert normalised("IO20: OFF → ON  S_OK  read back ON ✓   0.09 ms") == (
        "IO20: OFF → ON  S_OK  read back ON ✓   <ms> ms"
    )
    assert (
        normalised("07:26:20.341 ← 0,3,12↵   0.49 ms  S_OK") == "<clock> ← 0,3,12↵   <ms> ms  S_OK"
    )
    assert normalised("2026-11-22T01:43:20.317+00:00\tI0 = 0", numbers_vary=True) == (
        "<time>\tI0 = <n>"  # a name keeps its digits
    )
    assert (
        normalised("IO128            OK      <1s       ON  ")
        == "IO128            OK      <age>       ON"
    )
    assert not agrees(["I10: 0 → 5"], ["I10: 0 → 6"])
    assert agrees(['{"ok": true, ...}'], ['{"ok": true, "result": 0}'])
    assert not agrees(["a", "b"], ["a"])


def test_a_mark_that_cannot_be_read_is_refused() -> None:
    with pytest.raises(ValueError, match="repl, cli or console"):
        read_page("x.md", "<!-- sample: shell -->\n```\n$ ls\n```\n")
    with pytest.raises(ValueError, match="no such option"):
        read_page("x.md", "<!-- sample: cli; quickly -->\n```\n$ ls\n```\n")
    found = read_page(
        "x.md", "<!-- sample not checked: a controller -->\n```\n$ x\n```\n```\nsim> y\n```\n"
    )
    assert found.unchecked == [(2, "a controller")] and found.unmarked == [5]


# --------------------------------------------------------------------------- the REPL


def screen_lines(output: str) -> list[str]:
    """What a terminal shows of the REPL's output (a live table as last drawn)."""
    lines = Screen(WIDTH).feed(output).lines()
    while lines and not lines[-1]:
        lines.pop()
    return lines


def ended_since(repl: Driver, begun: int) -> Callable[[str], bool]:
    """Whether a live watch begun after ``begun`` others has ended."""
    return lambda _: repl.watches_ended > begun


async def repl_disagreement(sample: Sample, tmp_path: Path, settle: float = SETTLE) -> str | None:
    """The REPL run as the sample shows it: None when it printed the sample's lines, else
    why not. Lines typed are ``sim> LINE``; a live ``watch`` ends with Enter once its
    rows are drawn."""
    first, *rest = sample.lines
    assert first == "$ rac-console repl", f"{sample.name}: a REPL sample starts so"
    steps: list[tuple[str, list[str]]] = [("", [])]
    for line in rest:
        if line.startswith("sim>"):
            if line.removeprefix("sim>").strip():
                steps.append((line.removeprefix("sim>").strip(), []))
        else:
            steps[-1][1].append(line)
    expected: list[str] = []
    driver = Driver(tmp_path, timeout=30.0)
    driver.console = make_console(
        file=driver.out, force_terminal=True, width=WIDTH, color_system=None
    )

    async def settled(repl: Driver) -> None:
        deadline = time.monotonic() + settle
        while not agrees(expected, screen_lines(repl.out.getvalue()), sample.numbers_vary):
            if time.monotonic() > deadline:
                return
            await asyncio.sleep(0.02)

    async def run(repl: Driver) -> None:
        for typed, shown in steps:
            begun = repl.watches_begun
            if typed:
                repl.type(typed + "\r")
            expected.extend(shown)
            await settled(repl)
            if repl.watches_begun > begun:  # a live table: Enter returns to the prompt
                repl.type("\r")
                await repl.until(ended_since(repl, begun), f"{typed} to end")

    printed = screen_lines(await driver.run(run))
    if agrees(expected, printed, sample.numbers_vary):
        return None
    return difference(sample.name, expected, printed, sample.numbers_vary)


# ------------------------------------------------------------------------ the console


async def console_disagreement(sample: Sample, tmp_path: Path) -> str | None:
    """The console's results pane after the sample's line is typed."""
    assert sample.typed is not None
    app = make_app(tmp_path)
    echo = f"› {sample.typed}"

    def after() -> list[str]:
        lines = results_text(app).splitlines()
        return lines[lines.index(echo) + 1 :] if echo in lines else []

    async with app.run_test(size=(200, 50)) as pilot:
        await until(pilot, lambda: "type help" in results_text(app), "the welcome")
        await type_line(pilot, sample.typed)
        deadline = time.monotonic() + SETTLE
        while not agrees(list(sample.lines), after(), sample.numbers_vary):
            if time.monotonic() > deadline:
                break
            await pilot.pause(0.05)
        shown = after()
    if agrees(list(sample.lines), shown, sample.numbers_vary):
        return None
    return difference(sample.name, list(sample.lines), shown, sample.numbers_vary)


# ---------------------------------------------------------------------------- the CLI

#: rac-console in the sample's bash: this interpreter's, whatever is on the PATH.
PRELUDE = 'rac-console() { "$RAC_DOC_PYTHON" -m rac_console "$@"; }\n'


def cli_disagreement(sample: Sample, env: dict[str, str], cwd: Path) -> str | None:
    """Each ``$ COMMAND`` of the sample run in bash; a command shown without output (a
    pipe into ``jq``, a watch left running) is not run, unless ``echo $?`` follows it."""
    text = "\n".join(sample.lines)
    for port in sample.free_ports:  # the sample's port: one nothing listens on here
        text = re.sub(rf"\b{port}\b", str(unused_port()), text)
    commands: list[tuple[str, list[str]]] = []
    for line in text.splitlines():
        if line.startswith("$ "):
            commands.append((line[2:], []))
        else:
            assert commands, f"{sample.name}: a CLI sample starts with $ COMMAND"
            commands[-1][1].append(line)
    expected: list[str] = []
    printed: list[str] = []
    status = None
    for n, (command, shown) in enumerate(commands):
        if command == "echo $?":
            expected += [f"$ {command}", *shown]
            printed += [f"$ {command}", str(status)]
            continue
        checked = bool(shown) or (n + 1 < len(commands) and commands[n + 1][0] == "echo $?")
        if not checked:
            continue
        done = subprocess.run(
            ["bash", "-c", PRELUDE + command],
            env=env | {"RAC_DOC_PYTHON": sys.executable},
            cwd=cwd,
            capture_output=True,
            text=True,
            encoding="utf-8",
            timeout=60,
        )
        status = done.returncode
        # stderr's lines (each "rac-console: ...") before stdout's: the order a pipe
        # keeps between the two is not the order a terminal shows
        stderr_first = sorted(shown, key=lambda s: not s.startswith("rac-console: "))
        expected += [f"$ {command}", *stderr_first]
        printed += [f"$ {command}", *done.stderr.splitlines(), *done.stdout.splitlines()]
    if agrees(expected, printed, sample.numbers_vary):
        return None
    return difference(sample.name, expected, printed, sample.numbers_vary)


# ------------------------------------------------------------------------ the samples


@pytest.mark.slow
@pytest.mark.parametrize("sample", SAMPLES, ids=[s.name for s in SAMPLES])
async def test_the_sample_is_what_the_program_prints(
    sample: Sample, tmp_path: Path, env: dict[str, str]
) -> None:
    if sample.kind == "repl":
        wrong = await repl_disagreement(sample, tmp_path)
    elif sample.kind == "console":
        wrong = await console_disagreement(sample, tmp_path)
    else:
        if shutil.which("bash") is None:
            pytest.skip("the CLI's samples are bash")
        wrong = cli_disagreement(sample, env, tmp_path)
    assert wrong is None, wrong


#: The sample docs/repl.md held before issue 41, cut to its write.
OLD_REPL_SAMPLE = """\
$ rac-console repl
sim: no -H given: talking to the built-in RC8 simulator, not a controller. \
help lists the commands; Ctrl-D leaves.
sim> put IO 20 on
IO20 ← ON  S_OK   0.21 ms
sim>"""


@pytest.mark.slow
async def test_the_check_refuses_the_sample_repl_md_held_before(tmp_path: Path) -> None:
    old = read_page("docs/repl.md", f"<!-- sample: repl -->\n```\n{OLD_REPL_SAMPLE}\n```\n")
    wrong = await repl_disagreement(old.samples[0], tmp_path, settle=1.0)
    assert wrong is not None
    assert "-IO20 ← ON  S_OK   <ms> ms" in wrong
    assert "+IO20: OFF → ON  S_OK  read back ON ✓   <ms> ms" in wrong
