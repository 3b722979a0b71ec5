"""A command line is at most MAX_LINE characters in every front end (issue 42.1): a key
past it costs nothing and is not taken, the console says so once for a burst; a longer
line (a paste, a ``run`` file) is refused whole; every line that can make a RAC frame
fits, spaced as one likes."""

from __future__ import annotations

from pathlib import Path

import pytest
from textual import events

from rac_console.commands.line import MAX_LINE
from rac_console.protocol.request import MAX_FRAME
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.command_line import CommandLine
from tests.support.drivers import (
    Driver,
    FrameTap,
    burst,
    cli,
    make_app,
    results_text,
    until,
)

pytestmark = pytest.mark.slow

#: A long line that makes a frame: ten values of T, each written out in full decimal (the
#: smallest VT_R4), spaced as a person might line them up.
SMALLEST_R4 = "-0.000000000000000000000000000000000000000000001401298464324817"
LONGEST_PUT = "put  T  32767  " + "  ".join([SMALLEST_R4] * 9 + ["-1"])


def shown(app: RacConsoleApp) -> str:
    """The results, their lines wrapped at the screen's width joined again."""
    return " ".join(line.strip() for line in results_text(app).splitlines())


async def test_the_command_line_takes_no_key_past_its_length_and_says_so_once(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        line = app.query_one(CommandLine)
        burst(app, "a" * (MAX_LINE + 976))
        said = "holds at most 1,024 characters: 976 characters typed or pasted past that were not"
        await until(pilot, lambda: said in shown(app), "the line's length said")
        assert line.value == "a" * MAX_LINE
        assert results_text(app).count("holds at most") == 1


async def test_every_line_that_makes_a_frame_fits_and_is_sent(tmp_path: Path) -> None:
    assert len(LONGEST_PUT) < MAX_LINE
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        tap = FrameTap(tmp_path)
        burst(app, LONGEST_PUT + "\r")
        await until(pilot, lambda: any(f.startswith(b"PUT:") for f in tap.sent), "the put")
        put = next(frame for frame in tap.sent if frame.startswith(b"PUT:"))
        assert put.startswith(b"PUT:RC8:32767:T:8196,-1e-45,") and len(put) <= MAX_FRAME
        assert "holds at most" not in results_text(app)


async def test_a_pasted_line_too_long_is_refused_whole_and_shown_by_its_start(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        tap = FrameTap(tmp_path)
        app.query_one(CommandLine).post_message(events.Paste("get I 1 " + "1" * 2000 + "\n"))
        said = "a command line is at most 1024 characters: this one has 2,008"
        await until(pilot, lambda: said in shown(app), "the refusal")
        assert "› get I 1 111" in shown(app) and "(2,008 characters)" in shown(app)
        assert tap.sent == []


async def test_the_repl_line_takes_no_key_past_its_length(tmp_path: Path) -> None:
    driver = Driver(tmp_path, read_only=True)

    async def steps(d: Driver) -> None:
        d.type("get I 1" + " " * (MAX_LINE + 500))
        await d.until(lambda out: "holds at most 1,024 characters" in out, "the line's length")
        d.type("\r")
        await d.until(lambda out: "I1 = " in out, "the get, run")

    out = await driver.run(steps)
    assert out.count("holds at most") == 1


def test_a_run_file_line_too_long_is_refused(env: dict[str, str], tmp_path: Path) -> None:
    script = tmp_path / "lines.rac"
    script.write_text("get I 1 " + "1" * 2000 + "\n", encoding="utf-8")
    result = cli(env, "run", str(script))
    assert result.returncode == 2
    assert "a command line is at most 1024 characters: this one has 2,008" in result.stderr
