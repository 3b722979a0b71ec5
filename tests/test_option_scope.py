"""No option is silently ignored (issue 20, item 1): an option does what it says for the
command, before or after the command word, or is refused with exit 2 and one line
saying which commands take it. The real CLI, as a subprocess."""

from __future__ import annotations

import json
import sys
from datetime import datetime
from pathlib import Path

import pytest

from tests.support.drivers import cli, json_lines, one_error_line

pytestmark = pytest.mark.slow


def _times(stdout: str) -> list[datetime]:
    return [datetime.fromisoformat(line["time"]) for line in json_lines(stdout)]


@pytest.mark.parametrize("where", ["before", "after"])
def test_interval_spaces_get_repeats_in_either_position(
    where: str,
    env: dict[str, str],
) -> None:
    words = ["get", "I", "0", "-r", "3", "--json"]
    args = ["--interval", "0.3", *words] if where == "before" else [*words, "--interval", "0.3"]
    result = cli(env, *args)
    assert result.returncode == 0, result.stderr
    first, *_, last = _times(result.stdout)
    # Start to start 0.3 s: the third read cannot start before 0.6 s after the first.
    assert (last - first).total_seconds() >= 0.55, result.stdout


def test_interval_before_latency_paces_it(env: dict[str, str]) -> None:
    result = cli(env, "--json", "--interval", "0.2", "latency", "--count", "3")
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["count"] == 3
    # 3 GETs with a pause of 0.2 s between them: no more than 3 / 0.4 s = 7.5 a second.
    assert summary["requests_per_s"] <= 7.5, summary


def test_interval_before_watch_is_its_period(env: dict[str, str]) -> None:
    result = cli(env, "--interval", "0.3", "watch", "I", "0", "--count", "3", "--json")
    assert result.returncode == 0, result.stderr
    first, *_, last = _times(result.stdout)
    assert (last - first).total_seconds() >= 0.55


@pytest.mark.parametrize(
    ("words", "takes"),
    [
        (["--interval", "0.5", "put", "I", "1", "2"], "--interval is the time between"),
        (["--interval", "0.5", "send", "GET:RC8:1:I:"], "--interval is the time between"),
        (["--watch", "w.toml", "get", "I", "1"], "--watch loads a watch list"),
        (["--history", "h", "get", "I", "1"], "--history names the console's"),
        (["-H", "127.0.0.1", "sim"], "sim takes its own options"),
        (["--interval", "0.5", "get", "I", "0", "-r", "2", "-i", "0.1"], "given twice"),
    ],
)
def test_an_option_that_means_nothing_there_is_refused(
    words: list[str],
    takes: str,
    env: dict[str, str],
    tmp_path: Path,
) -> None:
    result = cli(env, *words)
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert takes in one_error_line(result)
    assert result.stdout == ""  # nothing was done: no read, no write


def test_json_and_yes_are_refused_for_the_console_at_a_terminal(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from rac_console.cli.main import parse_args
    from rac_console.cli.option_scope import refusal

    for stream in (sys.stdin, sys.stdout):
        monkeypatch.setattr(stream, "isatty", lambda: True)
    assert "--json prints results for scripts" in (refusal(parse_args(["--json"])) or "")
    assert "ask before every write" in (refusal(parse_args(["--yes", "repl"])) or "")
    assert refusal(parse_args(["--no-verify", "repl"])) is None  # the REPL's writes


def test_write_options_on_a_read_keep_an_alias_working(env: dict[str, str]) -> None:
    """``rac='rac-console --yes --no-verify'``: they change nothing for a get, as they say."""
    result = cli(env, "--yes", "--no-verify", "get", "I", "1")
    assert result.returncode == 0, result.stderr


def test_latency_takes_the_consoles_words_and_the_options(env: dict[str, str]) -> None:
    words = cli(env, "latency", "20", "I", "1", "--json")
    options = cli(env, "latency", "--count", "20", "--var", "I 1", "--json")
    for result in (words, options):
        assert result.returncode == 0, result.stderr
        summary = json.loads(result.stdout)
        assert summary["count"] == 20, summary
    assert "GET I1" in cli(env, "latency", "5", "I", "1").stdout
    both = cli(env, "latency", "5", "--var", "I 1")
    assert both.returncode == 2 and "not both" in one_error_line(both)
