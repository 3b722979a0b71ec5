"""Profiles in the REPL: the label on the prompt and the toolbar, the writes mode, and
the confirm question ``Write I10: 14 → 15 on Cell 3 — welding? [y/N]`` (default No),
driven through prompt-toolkit's pipe input against the real simulator.

The end-to-end test needs the write pipeline's confirm question (engine/exchange/writes.py).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from prompt_toolkit.completion import CompleteEvent
from prompt_toolkit.document import Document

from rac_console.commands.policy import WritePolicy, Writes
from rac_console.engine import CONFIRM_GUARD_SECONDS, ConfirmWrite
from rac_console.engine.published.status import LABEL_WIDTH
from rac_console.engine.setup.config import CONFIG_ENV, load_config
from rac_console.repl import asking as asking_module
from rac_console.repl.prompt_parts import confirm_message, prompt_fragments, toolbar_fragments
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import ANSWERABLE, Driver
from tests.support.samples import CELL3, SIM


def plain(fragments) -> str:
    return "".join(text for _, text, *_ in fragments)


def test_the_prompt_shows_the_label_in_the_profiles_colour() -> None:
    fragments = prompt_fragments(CELL3, lost=False)
    assert plain(fragments) == " Cell 3 — welding > "
    style = fragments[0][0]
    assert "bg:#800000" in style and "#ffffff" in style  # ANSI red, white ink on it
    assert plain(prompt_fragments(SIM, lost=False)) == "sim> "
    assert plain(prompt_fragments(replace(CELL3, label="\x1b]0;x\x07"), lost=False)).startswith(
        " \\x1b]0;x\\x07 "
    )
    unknown = prompt_fragments(replace(CELL3, colour="no_such_colour"), lost=False)
    assert "reverse" in unknown[0][0]


def test_the_toolbar_shows_label_target_and_writes() -> None:
    text = plain(toolbar_fragments(CELL3))
    assert "Cell 3 — welding" in text and "LIVE 192.168.0.1:5006" in text
    assert "CONFIRM WRITES" in text
    assert "writes open" in plain(toolbar_fragments(SIM))
    assert "READ-ONLY" in plain(toolbar_fragments(replace(CELL3, read_only=True)))


def test_the_question() -> None:
    question = ConfirmWrite(
        4, "I10", "14", "15", "PUT:RC8:10:I:3,15", "LIVE h:1", "Cell 3 — welding"
    )
    assert plain(confirm_message(question)) == "Write I10: 14 → 15 on Cell 3 — welding? [y/N] "
    unknown = replace(question, before=None, label=None)
    assert (
        plain(confirm_message(unknown)) == "Write I10: value now unknown → 15 on LIVE h:1? [y/N] "
    )


QUESTION = ConfirmWrite(9, "I10", "14", "15", "PUT:RC8:10:I:3,15", "LIVE h:1", "Cell 3")


@pytest.mark.slow  # over half a second
async def test_a_confirm_question_is_asked_and_answered(tmp_path: Path) -> None:
    driver = Driver(tmp_path, screen=True)
    answers: list[tuple[int, bool]] = []
    driver.engine.answer_confirm = lambda seq, yes: answers.append((seq, yes))  # type: ignore[method-assign]

    async def steps(d: Driver) -> None:
        for typed, expected in (("\r", False), ("n\r", False), ("y\r", True), ("yes\r", True)):
            asked = d.mark()
            d.engine.outbox.put_many([QUESTION])
            await d.answerable(asked)  # a yes sooner is asked again
            d.type(typed)
            await d.until(lambda _: len(answers) == len(seen) + 1, "the answer")
            seen.append(expected)
            assert d.repl.asking is None

    seen: list[bool] = []
    await driver.run(steps)
    assert answers == [(9, yes) for yes in (False, False, True, True)]


@pytest.mark.slow  # over half a second
async def test_a_confirm_target_writes_only_after_yes(tmp_path: Path) -> None:
    driver = Driver(
        tmp_path, screen=True, policy=WritePolicy(Writes.CONFIRM, source="profile cell3")
    )

    async def steps(d: Driver) -> None:
        asked = d.mark()
        d.type("put I 10 14\r")
        await d.answerable(asked)
        d.type("y\r")
        await d.until(lambda out: "read back 14" in out, "the first write")
        d.type("put I 10 15\r")
        await d.until(lambda _: d.repl.asking is not None, "the question")
        d.type("\r")  # the default: No
        await d.until(lambda out: "nothing was sent" in out, "the refusal")
        d.type("get I 10\r")
        await d.until(lambda out: "I10 = 14" in out, "the value kept")

    await driver.run(steps)
    assert b"PUT:RC8:10:I:3,15\r" not in driver.tap.sent


@pytest.mark.slow  # over half a second
async def test_a_yes_typed_right_after_the_question_is_not_taken(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """As in the console: a y within 0.4 s of the question came typed ahead, or pasted
    spread out over a slow link; it is not an answer."""
    driver = Driver(
        tmp_path, screen=True, policy=WritePolicy(Writes.CONFIRM, source="profile cell3")
    )

    async def steps(d: Driver) -> None:
        # "At once" is within the guard time however busy the machine: a guard of a
        # minute for the first answer (a y typed 0.4 s late would be a yes).
        monkeypatch.setattr(asking_module, "CONFIRM_GUARD_SECONDS", 60.0)
        d.type("put I 10 15\r")
        await d.until(lambda out: "? …" in out, "the question, waiting")
        d.type("y\r")  # at once
        await d.until(lambda out: "answer again" in out, "the question asked again")
        monkeypatch.setattr(asking_module, "CONFIRM_GUARD_SECONDS", CONFIRM_GUARD_SECONDS)
        assert b"PUT:RC8:10:I:3,15\r" not in d.tap.sent
        assert ANSWERABLE not in d.out.getvalue()  # it never said a yes would count
        await d.answerable(0)
        d.type("y\r")
        await d.until(lambda out: "read back 15" in out, "the write")

    await driver.run(steps)


def test_the_completer_offers_sim_and_the_profiles() -> None:
    from prompt_toolkit.document import Document

    from rac_console.repl.prompt_parts import RacCompleter

    completer = RacCompleter(lambda: (), [("cell3", "Cell 3 — welding")])
    found = [
        (c.text, c.display_meta_text)
        for c in completer.get_completions(Document("connect ", 8), None)  # type: ignore[arg-type]
    ]
    assert found == [("sim", "the built-in simulator"), ("cell3", "Cell 3 — welding")]


#: One character of the long label: shown nowhere else, one cell wide.
MARK = "Ŵ"


async def test_a_long_label_is_cut_wherever_the_repl_shows_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``rac-console -H cell3`` whose config file gives it a label of 10,000 characters."""
    with SimulatorThread() as cell:
        config = tmp_path / "config.toml"
        config.write_text(
            f'[target.cell3]\nhost = "{cell.host}"\nport = {cell.port}\n'
            f'label = "{MARK * 10_000}"\nwrites = "confirm"\n',
            encoding="utf-8",
        )
        monkeypatch.setenv(CONFIG_ENV, str(config))
        profiles = load_config().profiles
        profile = profiles["cell3"]
        driver = Driver(
            tmp_path,
            profile.host,
            port=profile.port,
            policy=profile.policy,
            profile=profile,
            profiles=profiles,
        )

        async def steps(d: Driver) -> None:
            d.type("connect cell3\r")
            await d.until(lambda out: "(profile cell3)" in out, "connected")
            assert d.repl.status is not None
            for fragments in (
                prompt_fragments(d.repl.status, lost=False),
                toolbar_fragments(d.repl.status),
            ):
                assert 0 < plain(fragments).count(MARK) <= LABEL_WIDTH
            completer = d.repl.prompt.completer
            assert completer is not None
            offered = {
                c.text: c.display_meta_text
                for c in completer.get_completions(Document("connect ", 8), CompleteEvent())
            }
            assert 0 < offered["cell3"].count(MARK) <= LABEL_WIDTH
            d.type("put I 10 15\r")
            await d.until(lambda _: d.repl.asking is not None, "the question")
            question = d.repl.asking
            assert question is not None and question.label == profile.label
            assert 0 < plain(confirm_message(question)).count(MARK) <= LABEL_WIDTH
            d.type("n\r")
            await d.until(lambda out: "nothing was sent" in out, "the refusal")

        out = await driver.run(steps)
    shown = [line for line in out.splitlines() if MARK in line]  # the banner, the connect
    assert len(shown) == 2, shown
    assert all(line.count(MARK) <= LABEL_WIDTH and "…" in line for line in shown), shown
