"""``-H bnech`` when the config file names a ``[target.bench]``: the failure to connect
says ``did you mean bench?``, as a mistyped command or option does.

The guess is made where every front end resolves a target (commands/target.py), so the
one-shot commands, ``run``, the REPL, the console and ``connect`` all say it: each is
checked here from the command line's own words (``-H bnech``) and config file.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.cli.main import parse_args, settle_targets
from rac_console.commands.policy import TargetProfile
from rac_console.commands.target import Target, resolve_target
from rac_console.engine import Engine
from rac_console.present.history import History
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import Driver, cli, one_error_line, profile, results_text, until

PROFILES = {
    "bench": TargetProfile("bench", "127.0.0.1", 5006),
    "cell3": TargetProfile("cell3", "127.0.0.1", 5007),
}
#: The config file: two profiles on ports nobody listens on (never reached here).
CONFIG = profile("bench", 1) + profile("cell3", 2)


def hint(host: str, where: str | None = "/x/config.toml") -> str | None:
    target = resolve_target(host, None, profiles=PROFILES, resolve=lambda h: None,
                            config_where=where)  # fmt: skip
    return target.unreachable_hint


def test_a_name_close_to_a_profiles_is_guessed() -> None:
    assert hint("bnech") == "no profile named bnech in /x/config.toml: did you mean bench?"
    assert hint("CEL3", None) == (
        "no profile named CEL3 (profiles: bench, cell3): did you mean cell3?"
    )


def test_a_name_close_to_none_guesses_nothing() -> None:
    assert hint("robot") == "no profile named robot in /x/config.toml"
    assert hint("10.0.0.9") is None  # an address is no misspelt profile
    assert "did you mean" not in (
        resolve_target("bnech", None, profiles={}, config_where=None).unreachable_hint or ""
    )


@pytest.mark.slow
def test_one_shot_commands_and_run_say_it(
    env: dict[str, str], config: Callable[[str], Path]
) -> None:
    config(CONFIG)
    result = cli(env, "-H", "bnech", "--timeout", "1", "get", "I", "1")
    assert result.returncode == 3
    assert "no profile named bnech" in one_error_line(result)
    assert "did you mean bench?" in one_error_line(result)
    script = cli(env, "-H", "bnech", "--timeout", "1", "run", "-", stdin="get I 1\n")
    assert "did you mean bench?" in script.stderr, script.stderr


def target_of_the_command_line(env: dict[str, str], monkeypatch: pytest.MonkeyPatch) -> Target:
    """The target ``rac-console -H bnech`` settles on, as the console and the REPL get it."""
    monkeypatch.setenv("RAC_CONSOLE_CONFIG", env["RAC_CONSOLE_CONFIG"])
    args = parse_args(["-H", "bnech"])
    assert settle_targets(args) is None  # one target
    assert isinstance(args.target, Target)
    return args.target


@pytest.mark.slow
async def test_the_repl_says_it(
    tmp_path: Path,
    env: dict[str, str],
    config: Callable[[str], Path],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    config(CONFIG)
    target = target_of_the_command_line(env, monkeypatch)
    driver = Driver(tmp_path, target=target, timeout=1.0)

    async def steps(repl: Driver) -> None:
        repl.type("get I 1\r")
        await repl.until(lambda out: "did you mean bench?" in out, "the guess")

    said = await driver.run(steps)
    assert "no profile named bnech" in said


@pytest.mark.slow
async def test_the_console_says_it(
    tmp_path: Path,
    env: dict[str, str],
    config: Callable[[str], Path],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    config(CONFIG)
    target = target_of_the_command_line(env, monkeypatch)
    engine = Engine(target=target, timeout=1.0, interval=0.05, cycles=True)
    app = RacConsoleApp(engine, History(tmp_path / "history"))
    async with app.run_test(size=(160, 40)) as pilot:

        def said() -> str:  # the results pane wraps a long line: read it as one
            return " ".join(results_text(app).split())

        await until(pilot, lambda: "did you mean bench?" in said(), "the guess")
        assert "no profile named bnech" in said()
