"""Profiles in the console (Pilot): the label and colour around the screen and on the
status line, ``connect NAME`` and ``connect sim``, and the confirm modal a typed-ahead
Enter cannot answer.

A second simulator on 127.0.0.1 port 0 plays the controller a profile names. The
end-to-end confirm tests need the write pipeline's confirm question (engine/exchange/writes.py).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest
from textual import events
from textual.widgets import Static

from rac_console.commands.policy import TargetProfile, WritePolicy, Writes
from rac_console.engine import ConfirmWrite
from rac_console.engine.published.status import LABEL_WIDTH
from rac_console.engine.setup.config import CONFIG_ENV, load_config
from rac_console.sim.thread import SimulatorThread
from rac_console.tui import confirm_screen
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.confirm_screen import ConfirmWriteScreen
from tests.support.drivers import (
    ANSWERABLE,
    FrameTap,
    answerable,
    console,
    modal,
    question_keys,
    results_text,
    type_line,
    until,
)

#: Terminal apps: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow


@pytest.fixture
def cell() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


def cell3(cell: SimulatorThread, colour: str | None = "red", writes: Writes = Writes.CONFIRM):
    return TargetProfile(
        "cell3", cell.host, cell.port, "Cell 3 — welding", colour, WritePolicy(writes)
    )


def status_line(app: RacConsoleApp) -> str:
    app.main_screen.refresh_table()
    return str(app.main_screen.panes.status_bar.line.plain)


class Answers:
    """What the console answered the engine's confirm questions."""

    def __init__(self, app: RacConsoleApp) -> None:
        self.given: list[tuple[int, bool]] = []
        answer = app.main_screen.members.engine.answer_confirm

        def spy(seq: int, yes: bool) -> None:
            self.given.append((seq, yes))
            answer(seq, yes)

        app.main_screen.members.engine.answer_confirm = spy  # type: ignore[method-assign]


QUESTION = ConfirmWrite(7, "I10", "14", "15", "PUT:RC8:10:I:3,15", "LIVE 10.0.0.1:5006", "Cell 3")


async def question_up(pilot, app: RacConsoleApp, accepting: bool = False) -> ConfirmWriteScreen:
    await until(pilot, lambda: modal(app) is not None, "the confirm question")
    screen = modal(app)
    assert screen is not None
    await until(pilot, lambda: screen.shown, "the question on screen")
    if accepting:
        await answerable(pilot, screen)
    return screen


# ------------------------------------------------------------ target shown


async def test_a_profile_frames_the_console_in_its_colour_with_its_label(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = console(tmp_path, cell3(cell))
    async with app.run_test(size=(100, 30)) as pilot:
        await until(
            pilot,
            lambda: (
                app.main_screen.status is not None
                and app.main_screen.status.connection == "connected"
            ),
            "connected",
        )
        screen = app.screen_stack[0]
        assert screen.has_class("-profile")
        assert str(screen.styles.border.top[1]) == str(confirm_screen.border_colour("red"))  # type: ignore[attr-defined]
        assert screen.border_title == " Cell 3 — welding "
        line = status_line(app)
        assert line.startswith(" Cell 3 — welding   LIVE 127.0.0.1:")
        assert "CONFIRM WRITES" in line


async def test_connect_sim_and_connect_name_in_the_console(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    profile = cell3(cell, colour="#00875f", writes=Writes.READ_ONLY)
    app = console(tmp_path, profiles={"cell3": profile})
    async with app.run_test(size=(100, 30)) as pilot:
        await until(pilot, lambda: app.main_screen.status is not None, "the first status")
        screen = app.screen_stack[0]
        assert not screen.has_class("-profile") and screen.border_title is None
        assert "writes open" in status_line(app)
        await type_line(pilot, "connect cell3")
        await until(
            pilot,
            lambda: (
                app.main_screen.status is not None and app.main_screen.status.profile == "cell3"
            ),
            "cell3",
        )
        assert screen.has_class("-profile") and screen.border_title == " Cell 3 — welding "
        assert str(screen.styles.border.top[1]) == str(confirm_screen.border_colour("#00875f"))  # type: ignore[attr-defined]
        line = status_line(app)
        assert line.startswith(" Cell 3 — welding   LIVE") and " READ-ONLY " in line
        await until(
            pilot,
            lambda: "connected to Cell 3 — welding (profile cell3)" in results_text(app),
            "said",
        )
        await type_line(pilot, "connect sim")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.is_simulator,
            "the simulator",
        )
        assert not screen.has_class("-profile") and screen.border_title is None
        assert screen.styles.border.top[0] in ("", "none")
        assert status_line(app).startswith(" SIMULATOR (built-in)  writes open ")


async def test_an_unknown_colour_keeps_the_default_frame(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = console(tmp_path, cell3(cell, colour="no_such_colour"))
    async with app.run_test(size=(100, 30)) as pilot:
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.label is not None,
            "status",
        )
        await pilot.pause()
        screen = app.screen_stack[0]
        assert screen.has_class("-profile") and screen.border_title == " Cell 3 — welding "
        assert screen.styles.border.top[0] == "heavy"  # the stylesheet's, in $accent
        assert status_line(app).startswith(" Cell 3 — welding ")


# ------------------------------------------------------------- the modal


async def test_the_question_shows_target_values_request_and_default_no(tmp_path: Path) -> None:
    app = console(tmp_path)
    answers = Answers(app)
    async with app.run_test(size=(100, 30)) as pilot:
        app.main_screen.confirm_write(QUESTION)
        screen = await question_up(pilot, app)
        shown = "\n".join(str(w.content) for w in screen.query(Static))
        for part in ("LIVE 10.0.0.1:5006", "I10: 14 → 15", "PUT:RC8:10:I:3,15", "0.4 s"):
            assert part in shown
        assert "Cell 3" in str(screen.query_one("#confirm-box").border_title)
        assert app.focused is None  # nothing to press with Enter
        await answerable(pilot, screen)
        assert "Enter, n or Esc: no" in question_keys(screen)
        await pilot.press("enter")
        await until(pilot, lambda: answers.given == [(7, False)], "the answer")
        assert modal(app) is None
        assert app.focused is app.main_screen.panes.command_line


async def test_an_unknown_value_before_is_said(tmp_path: Path) -> None:
    app = console(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        app.main_screen.confirm_write(
            ConfirmWrite(3, "I10", None, "15", "PUT:RC8:10:I:3,15", "x", None)
        )
        screen = await question_up(pilot, app)
        assert "I10: value now unknown → 15" in str(
            screen.query_one("#confirm-question", Static).content
        )


async def test_keys_typed_before_the_question_or_in_its_guard_time_answer_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(confirm_screen, "GUARD_SECONDS", 30.0)  # the whole test is "too soon"
    app = console(tmp_path)
    answers = Answers(app)
    async with app.run_test(size=(100, 30)) as pilot:
        early = [events.Key("enter", "\r"), events.Key("y", "y")]  # typed before it showed
        app.main_screen.confirm_write(QUESTION)
        screen = await question_up(pilot, app)
        for key in early:
            app.post_message(key)
        await pilot.press("y", "enter", "Y", "n")  # and within the guard time
        await pilot.pause()
        assert screen.ignored == 6
        assert answers.given == [] and modal(app) is screen
        await pilot.press("escape")  # Esc answers No at once
        await until(pilot, lambda: answers.given == [(7, False)], "the answer")


@pytest.mark.parametrize("key", ["escape", "n"])
async def test_esc_and_n_answer_no(tmp_path: Path, key: str) -> None:
    app = console(tmp_path)
    answers = Answers(app)
    async with app.run_test(size=(100, 30)) as pilot:
        app.main_screen.confirm_write(QUESTION)
        await question_up(pilot, app, accepting=True)
        await pilot.press("x", key)  # a key that means nothing is ignored
        await until(pilot, lambda: answers.given == [(7, False)], "the answer")


async def test_y_after_the_guard_time_and_the_yes_button_answer_yes(tmp_path: Path) -> None:
    app = console(tmp_path)
    answers = Answers(app)
    async with app.run_test(size=(100, 30)) as pilot:
        app.main_screen.confirm_write(QUESTION)
        await question_up(pilot, app, accepting=True)
        await pilot.press("y")
        await until(pilot, lambda: answers.given == [(7, True)], "the answer")
        app.main_screen.confirm_write(QUESTION)
        await question_up(pilot, app, accepting=True)
        await pilot.click("#confirm-yes")
        await until(pilot, lambda: answers.given == [(7, True), (7, True)], "the click")


# ---------------------------------------------- end to end (with the pipeline)


async def test_a_confirm_target_declines_by_default_and_typed_ahead_keys_do_not_accept(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    cell.server.controller.handle(b"PUT:RC8:10:I:3,14")
    app = console(tmp_path, cell3(cell))
    answers = Answers(app)
    tap = FrameTap(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await until(
            pilot,
            lambda: (
                app.main_screen.status is not None
                and app.main_screen.status.connection == "connected"
            ),
            "connected",
        )
        await type_line(pilot, "put I 10 15", enter=False)
        await pilot.press("enter", "enter", "y", "enter", "y")  # one burst: Enter, then y
        # Pilot paces keys by the app's idle time: the burst may end before the question
        # shows (the keys went to the command line), inside its guard time (ignored), or,
        # on a slow run, reach it after (Enter first: No). Whichever: nothing is accepted.
        await until(pilot, lambda: modal(app) is not None or bool(answers.given), "the question")
        screen = modal(app)
        if screen is not None:
            await until(pilot, lambda: screen.shown, "the question on screen")  # type: ignore[union-attr]
            assert "I10: 14 → 15" in str(screen.query_one("#confirm-question", Static).content)
            await answerable(pilot, screen)
            assert modal(app) is screen, answers.given  # the burst answered nothing
            await pilot.press("enter")  # the default: No
        await until(pilot, lambda: len(answers.given) == 1, "the answer")
        assert answers.given[0][1] is False
        await until(pilot, lambda: "nothing was sent" in results_text(app), "the refusal")
        assert b"PUT:RC8:10:I:3,15\r" not in tap.sent
        app.main_screen.panes.command_line.clear()
        await type_line(pilot, "get I 10")
        await until(pilot, lambda: "I10 = 14" in results_text(app), "the value kept")

        await type_line(pilot, "put I 10 15")
        screen = await question_up(pilot, app, accepting=True)
        await pilot.press("y")
        await until(pilot, lambda: b"PUT:RC8:10:I:3,15\r" in tap.sent, "the write")
        await type_line(pilot, "get I 10")
        await until(pilot, lambda: "I10 = 15" in results_text(app), "the value written")


async def test_a_y_pressed_when_the_question_says_y_N_writes_however_long_its_guard(
    tmp_path: Path, cell: SimulatorThread, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Whoever answers at the first sight of ``[y/N]`` is answering a question that
    takes the answer: the marker shows once a y counts, never while keys are ignored.
    The guard time is held open for 2 s, so that a ``[y/N]`` shown from the start would
    be answered well inside it (the y ignored, nothing written)."""
    monkeypatch.setattr(confirm_screen, "GUARD_SECONDS", 2.0)
    app = console(tmp_path, cell3(cell))
    tap = FrameTap(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await type_line(pilot, "put I 10 15")
        await until(pilot, lambda: modal(app) is not None, "the question")
        screen = modal(app)
        assert screen is not None
        await until(pilot, lambda: ANSWERABLE in question_keys(screen), "[y/N] on the question")
        await pilot.press("y")
        await until(pilot, lambda: "read back 15" in results_text(app), "the write read back")
        assert b"PUT:RC8:10:I:3,15\r" in tap.sent


async def test_tab_completes_profile_names_after_connect(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    app = console(tmp_path, profiles={"cell3": cell3(cell)})
    async with app.run_test(size=(100, 30)) as pilot:
        await type_line(pilot, "connect c", enter=False)
        await pilot.press("tab")
        assert app.main_screen.panes.command_line.value == "connect cell3 "


# ------------------------------------------------------------- a long label

#: One character of the long label: shown nowhere else, one cell wide.
MARK = "Ŵ"


def long_label_profile(
    tmp_path: Path, cell: SimulatorThread, monkeypatch: pytest.MonkeyPatch
) -> TargetProfile:
    """``[target.cell3]`` with a label of 10,000 characters, read from a config file named
    by RAC_CONSOLE_CONFIG as ``rac-console -H cell3`` reads it."""
    config = tmp_path / "config.toml"
    config.write_text(
        f'[target.cell3]\nhost = "{cell.host}"\nport = {cell.port}\nlabel = "{MARK * 10_000}"\n'
        'colour = "red"\n',
        encoding="utf-8",
    )
    monkeypatch.setenv(CONFIG_ENV, str(config))
    profile = load_config().profiles["cell3"]
    assert profile.label == MARK * 10_000
    return profile


async def test_a_long_label_is_cut_wherever_the_console_shows_it(
    tmp_path: Path, cell: SimulatorThread, monkeypatch: pytest.MonkeyPatch
) -> None:
    profile = long_label_profile(tmp_path, cell, monkeypatch)
    app = console(tmp_path, profile)
    async with app.run_test(size=(100, 30)) as pilot:
        await until(pilot, lambda: "LIVE controller" in results_text(app), "the welcome")
        shown = results_text(app).count(MARK)
        assert 0 < shown <= LABEL_WIDTH, shown  # the welcome names the profile's label once
        assert "…" in results_text(app)
        await type_line(pilot, "connect ", enter=False)
        await pilot.press("tab")  # two candidates: listed, each with its help
        await until(
            pilot, lambda: app.main_screen.panes.completions.has_class("-visible"), "the candidates"
        )
        listed = str(app.main_screen.panes.completions.render())
        assert "cell3" in listed and 0 < listed.count(MARK) <= LABEL_WIDTH
        await pilot.press("c", "e", "l", "l", "3")
        await pilot.press("enter")
        await until(pilot, lambda: "(profile cell3)" in results_text(app), "connected")
        assert 0 < results_text(app).count(MARK) - shown <= LABEL_WIDTH
        assert str(app.screen_stack[0].border_title).count(MARK) <= LABEL_WIDTH
        assert status_line(app).count(MARK) <= LABEL_WIDTH
        app.main_screen.confirm_write(replace(QUESTION, label=profile.label))
        screen = await question_up(pilot, app)
        title = str(screen.query_one("#confirm-box").border_title)
        assert 0 < title.count(MARK) <= LABEL_WIDTH
        shown_in_modal = "\n".join(str(w.content) for w in screen.query(Static))
        assert shown_in_modal.count(MARK) <= LABEL_WIDTH
