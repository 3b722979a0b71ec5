"""History keeps what ran: a line refused before anything was sent (an unknown command,
bad syntax, a write the target's rules refuse) is recalled by Up in this session, to be
fixed, but never suggested and never written to the file (issue 20)."""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.commands.language import Get, Put, VarRef
from rac_console.commands.outcome import ExitStatus, Outcome, refused
from rac_console.engine import Message, Result, UiStep
from rac_console.present.history import History, is_refused
from rac_console.protocol import Variant, kind_of


def test_a_refused_line_is_recalled_but_not_suggested_nor_kept(tmp_path: Path) -> None:
    path = tmp_path / "history"
    history = History(path)
    history.enter("get I 1")
    history.settle("get I 1", refused=False)
    history.enter("gte I 1")
    history.settle("gte I 1", refused=True)
    assert history.entries == ["get I 1", "gte I 1"]  # Up recalls the typo, to fix it
    assert history.suggest("g") == "get I 1"  # not the newer, refused line
    assert history.suggest("gt") is None
    assert path.read_text().splitlines() == ["get I 1"]
    assert History(path).entries == ["get I 1"]  # the next session never sees it


def test_a_line_is_written_once_it_ran_not_when_entered(tmp_path: Path) -> None:
    path = tmp_path / "history"
    history = History(path)
    history.enter("get I 1")
    history.enter("put I 1 5")  # typed ahead while the get runs
    assert history.entries == ["get I 1", "put I 1 5"]
    assert not path.exists()
    history.settle("get I 1", refused=False)
    history.settle("put I 1 5", refused=False)
    assert path.read_text().splitlines() == ["get I 1", "put I 1 5"]


def test_a_line_refused_once_and_run_later_is_suggested_again(tmp_path: Path) -> None:
    history = History(tmp_path / "history")
    history.enter("put I 1 5")
    history.settle("put I 1 5", refused=True)  # read-only target
    assert history.suggest("pu") is None
    history.enter("put I 1 5")
    history.settle("put I 1 5", refused=False)  # after connect to a writable one
    assert history.suggest("pu") == "put I 1 5"


def test_a_line_never_entered_settles_nothing(tmp_path: Path) -> None:
    """A line made by a key on a row was never typed: its result writes nothing."""
    path = tmp_path / "history"
    history = History(path)
    history.settle("put IO 3 on", refused=False)
    assert history.entries == [] and not path.exists()


def test_append_still_keeps_a_line_at_once(tmp_path: Path) -> None:
    path = tmp_path / "history"
    history = History(path)
    history.append("get S 1")
    history.append("get S 1")
    assert history.suggest("get S 1") is None  # the line itself is no suggestion
    assert history.suggest("ge") == "get S 1"
    assert path.read_text().splitlines() == ["get S 1"]


VAR = VarRef(kind_of("I"), 1)


def test_which_results_are_refused() -> None:
    unknown = Result(1, (Message("unknown command 'gte'", "error"),), "gte I 1", None)
    assert is_refused(unknown)
    put = Put.of(VAR, Variant(3, 5), "5")
    read_only = Result(2, (refused("put I 1 5", "PUT refused: read-only"),), "put I 1 5", put)
    assert is_refused(read_only)
    not_connected = Result(3, (Message("not connected", "error"),), "get I 1", Get(VAR))
    assert not is_refused(not_connected)  # the line is right; the state was not
    timed_out = Outcome("GET:RC8:1:I:", ExitStatus.TRANSPORT, error="timed out")
    assert not is_refused(Result(4, (timed_out,), "get I 1", Get(VAR)))
    assert not is_refused(Result(5, (UiStep.QUIT,), "quit", None))
    assert not is_refused(Result(6, (), "# a comment", None))


@pytest.mark.slow  # over half a second
async def test_the_console_does_not_suggest_a_refused_line(tmp_path: Path) -> None:
    from tests.support.drivers import make_app, results_text, type_line, until

    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await type_line(pilot, "get S 1")
        await type_line(pilot, "gte S 1")
        await until(pilot, lambda: "did you mean get?" in results_text(app), "the refusal")
        await type_line(pilot, "g", enter=False, keys=True)
        await until(
            pilot, lambda: app.main_screen.panes.command_line._suggestion != "", "a suggestion"
        )
        assert app.main_screen.panes.command_line._suggestion == "get S 1"
        await pilot.press("ctrl+u", "up")
        assert app.main_screen.panes.command_line.value == "gte S 1"  # recalled, to be fixed
    assert (tmp_path / "history").read_text().splitlines() == ["get S 1"]
