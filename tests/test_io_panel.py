"""The I/O grid (F5) in the console, against the built-in simulator.

At start the simulator has IO 128, 130 and 131 ON; IO 0-7 move by themselves.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.present.iogrid import GridLine
from rac_console.sim.thread import SimulatorThread
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.io_panel import IoPanel
from tests.support.drivers import FrameTap, make_app, results_text, type_line, until
from tests.support.servers import Valve

#: A console, a simulator and polls: a few seconds per test.
pytestmark = pytest.mark.slow


def line_at(app: RacConsoleApp, start: int) -> GridLine | None:
    grid = app.main_screen.panes.io_panel.grid
    if grid is None:
        return None
    return next((line for line in grid.lines if line.start == start), None)


def word_is(app: RacConsoleApp, start: int, value: int) -> bool:
    line = line_at(app, start)
    return line is not None and line.word.complete and line.word.value == value


def grid_text(app: RacConsoleApp) -> str:
    return (
        app.main_screen.panes.io_panel.grid.text.plain
        if app.main_screen.panes.io_panel.grid is not None
        else ""
    )


def io_rows_in_table(app: RacConsoleApp) -> int:
    return sum(1 for key in app.main_screen.panes.table.rows if str(key.value).startswith("IO"))


async def watch_all_ok(pilot, line: str, count: int) -> None:
    app = pilot.app
    await type_line(pilot, line)
    await until(
        pilot,
        lambda: (
            len(app.main_screen.members.rows) == count
            and all(v.status == "OK" for v in app.main_screen.members.rows.values())
        ),
        f"the first values of {line}",
    )


async def test_f5_shows_the_bits_and_the_word_then_gives_the_rows_back(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await watch_all_ok(pilot, "watch IO 128-143", 16)
        await until(pilot, lambda: io_rows_in_table(app) == 16, "the IO rows in the table")
        assert not app.main_screen.panes.io_panel.display

        await pilot.press("f5")
        await until(pilot, lambda: word_is(app, 128, 0b1101), "word 0x000D in the grid")
        line = line_at(app, 128)
        assert line is not None
        assert [bit.index for bit in line.bits if bit.state.value == "on"] == [128, 130, 131]
        assert "0x000D" in grid_text(app) and " 13" in grid_text(app)
        assert (
            app.main_screen.panes.io_panel.display
            and app.main_screen.panes.io_panel.region.height >= 3
        )
        assert io_rows_in_table(app) == 0

        await type_line(pilot, "put IO 129 on")
        await until(pilot, lambda: word_is(app, 128, 0b1111), "IO 129 ON in the word (0x000F)")
        assert "0x000F" in grid_text(app)

        await pilot.press("f5")
        await until(pilot, lambda: io_rows_in_table(app) == 16, "the IO rows back in the table")
        assert not app.main_screen.panes.io_panel.display


async def test_80x24_shows_64_bits_and_the_rest_of_the_screen(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await watch_all_ok(pilot, "watch IO 128-191", 64)
        await pilot.press("f5")
        await until(pilot, lambda: len(grid_text(app).splitlines()) == 4, "4 lines of 16")
        await pilot.pause(0.1)
        panel = app.main_screen.panes.io_panel
        assert panel.grid is not None and panel.grid.layout.per_line == 16
        assert panel.scrollable_content_region.height >= 4  # every line in view
        for widget in (
            app.main_screen.panes.status_bar,
            app.main_screen.panes.frame_log,
            app.main_screen.panes.results,
            app.main_screen.panes.command_line,
        ):
            assert widget.region.height >= 1, widget
        assert app.main_screen.panes.frame_log.region.y > panel.region.bottom - 1
        assert app.screen.query_one("Footer").region.y == 23


async def test_wide_terminal_puts_the_grid_beside_the_table(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(200, 50)) as pilot:
        await watch_all_ok(pilot, "watch IO 0-15", 16)
        await pilot.press("f5")
        await until(pilot, lambda: app.main_screen.panes.io_panel.grid is not None, "the grid")
        await pilot.pause(0.1)
        assert app.main_screen.panes.io_panel.region.x > app.main_screen.panes.table.region.x
        assert app.main_screen.panes.io_panel.region.y == app.main_screen.panes.table.region.y


async def test_space_toggles_the_bit_under_the_cursor_once_per_flight(tmp_path: Path) -> None:
    with SimulatorThread() as sim:
        valve = Valve(sim.host, sim.port)
        try:
            # The write stays in flight while the valve holds the simulator's answers (a
            # long timeout: the test says how long, not a clock that load can outrun).
            await _one_write_per_flight(
                make_app(tmp_path, sim.host, valve.port, timeout=60), valve, tmp_path
            )
        finally:
            valve.close()


async def _one_write_per_flight(app: RacConsoleApp, valve: Valve, tmp_path: Path) -> None:
    tap = FrameTap(tmp_path)

    def writes() -> list[bytes]:
        return [s for s in tap.sent if s.startswith(b"PUT:RC8:129:IO:")]

    async with app.run_test(size=(120, 40)) as pilot:
        await watch_all_ok(pilot, "watch IO 128-143", 16)
        await pilot.press("f5")
        await until(pilot, lambda: word_is(app, 128, 0b1101), "the first word")
        # Paused, no poll can show the write: it stays in flight through the burst.
        await type_line(pilot, "pause")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.paused,
            "the pause",
        )
        valve.shut()  # the controller's answers held: the write and its read-back wait
        app.main_screen.panes.io_panel.focus()
        await pilot.pause()
        assert app.main_screen.panes.io_panel.cursor == 128
        await pilot.press("right")  # IO 129, OFF
        assert app.main_screen.panes.io_panel.cursor == 129
        assert str(app.main_screen.panes.io_panel.border_subtitle).startswith(
            "IO 129 OFF"
        )  # its state too

        await pilot.press("space", "space", "space")  # a burst: one write
        await until(
            pilot,
            lambda: results_text(app).count("the last toggle has not come back yet") == 2,
            "the two refusals",
        )
        await until(pilot, lambda: len(writes()) == 1, "the write")
        assert writes() == [b"PUT:RC8:129:IO:11,-1\r"]
        await until(
            pilot,
            lambda: (
                app.main_screen.panes.io_panel.grid is not None
                and "underline" in str(app.main_screen.panes.io_panel.grid.text.spans)
            ),
            "the bit drawn as in flight",
        )
        valve.open()

        await pilot.press("escape")  # back to the command line
        await type_line(pilot, "resume")
        await until(pilot, lambda: word_is(app, 128, 0b1111), "IO 129 ON")
        await until(
            pilot,
            lambda: (
                not any(
                    app.main_screen.members.toggles.busy(var)
                    for var in app.main_screen.members.rows
                )
            ),
            "no toggle in flight",
        )
        app.main_screen.panes.io_panel.focus()
        await pilot.press("space")  # now ON: writes OFF
        await until(pilot, lambda: word_is(app, 128, 0b1101), "IO 129 OFF again")
        assert writes() == [b"PUT:RC8:129:IO:11,-1\r", b"PUT:RC8:129:IO:11,0\r"]


async def test_arrows_keep_to_the_lines(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await watch_all_ok(pilot, "watch IO 128-159", 32)
        await pilot.press("f5")
        await until(pilot, lambda: len(grid_text(app).splitlines()) == 2, "two lines")
        panel = app.query_one(IoPanel)
        panel.focus()
        await pilot.pause()
        await pilot.press("left")
        assert panel.cursor == 128
        await pilot.press("down")
        assert panel.cursor == 144
        await pilot.press("down", "right")
        assert panel.cursor == 145
        await pilot.press("up", "left", "left")
        assert panel.cursor == 128
        await pilot.press("escape")
        assert app.main_screen.panes.command_line.has_focus
