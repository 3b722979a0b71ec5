"""Keys on the watch table and the trend view, with Pilot against the built-in simulator."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from textual.pilot import Pilot

from rac_console.present.trends import span_text
from rac_console.sim.thread import SimulatorThread
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.trend_view import TrendView
from tests.support.drivers import FrameTap, make_app, results_text, type_line, until
from tests.support.servers import Valve

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

SIZE = (140, 40)


async def watch(pilot: Pilot, line: str, rows: int) -> None:
    """Watch, and wait until the table shows every row with its first value."""
    app = pilot.app
    assert isinstance(app, RacConsoleApp)
    await type_line(pilot, line)
    await until(
        pilot,
        lambda: (
            app.main_screen.panes.table.row_count == rows
            and all(view.status == "OK" for view in app.main_screen.members.rows.values())
            and "OK" in str(app.main_screen.panes.table.get_cell_at((rows - 1, 2)))  # type: ignore[arg-type]
        ),
        f"{rows} rows with values",
    )


def keys(app: RacConsoleApp) -> list[str]:
    return [
        str(app.main_screen.panes.table.get_row_at(n)[0])
        for n in range(app.main_screen.panes.table.row_count)
    ]


def cursor(app: RacConsoleApp) -> str | None:
    view = app.main_screen.panes.table.cursor_view()
    return view.key if view is not None else None


def puts(tap: FrameTap) -> list[bytes]:
    return [frame for frame in tap.sent if frame.startswith(b"PUT")]


def polls(tap: FrameTap) -> int:
    return sum(1 for frame in tap.sent if frame.startswith(b"GET"))


async def test_f6_moves_between_panes_and_the_cursor_shows_only_in_the_table(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await watch(pilot, "watch IO 128-129", 2)
        assert app.focused is app.main_screen.panes.command_line
        assert not app.main_screen.panes.table.show_cursor  # no cursor drawn while unfocused
        await pilot.press("f6")
        assert (
            app.focused is app.main_screen.panes.table and app.main_screen.panes.table.show_cursor
        )
        await pilot.press("f6")
        assert (
            app.focused is app.main_screen.panes.frame_log
            and not app.main_screen.panes.table.show_cursor
        )
        await pilot.press("f6")
        assert app.focused is app.main_screen.panes.command_line
        await pilot.press("shift+f6")
        assert app.focused is app.main_screen.panes.frame_log
        await pilot.press("shift+tab")
        assert app.focused is app.main_screen.panes.table
        await pilot.press("tab")
        assert app.focused is app.main_screen.panes.frame_log
        await pilot.press("escape")
        assert app.focused is app.main_screen.panes.command_line
        await pilot.press("f6", "escape")
        assert app.focused is app.main_screen.panes.command_line
        await pilot.press("tab")  # in the command line: completion, not focus
        assert app.focused is app.main_screen.panes.command_line


async def test_enter_puts_the_rows_value_on_the_command_line_and_sends_nothing(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        tap = FrameTap(tmp_path)
        await watch(pilot, "watch P 1 pick", 1)
        await pilot.press("f6", "enter")
        line = "put P 1 350 0 450 180 0 180 5"
        assert app.main_screen.panes.command_line.value == line
        assert app.main_screen.panes.command_line.cursor_position == len(line)
        assert app.main_screen.panes.command_line.selection.is_empty
        assert app.focused is app.main_screen.panes.command_line
        before = polls(tap)
        await until(pilot, lambda: polls(tap) >= before + 3, "three more polls")
        assert puts(tap) == []
        assert "› put" not in results_text(app)


async def test_enter_on_a_row_without_a_value_leaves_the_hint(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await type_line(pilot, "pause")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.paused,
            "the pause",
        )
        await type_line(pilot, "watch P 2")
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 1, "the row")
        await pilot.press("f6", "enter")
        assert app.main_screen.panes.command_line.value == "put P 2 "
        await until(
            pilot,
            lambda: app.main_screen.panes.command_line._suggestion == "put P 2 X Y Z Rx Ry Rz Fig",
            "the hint of what put P needs",
        )


async def test_space_toggles_an_io_bit_through_the_typed_put_path(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        tap = FrameTap(tmp_path)
        await watch(pilot, "watch IO 128", 1)
        assert app.main_screen.panes.table.get_cell("IO128", "value").plain.strip() == "ON"  # type: ignore[attr-defined]
        await pilot.press("f6", "space")
        await until(pilot, lambda: puts(tap) == [b"PUT:RC8:128:IO:11,0\r"], "the PUT on the wire")
        await until(
            pilot,
            lambda: app.main_screen.panes.table.get_cell("IO128", "value").plain.strip() == "OFF",  # type: ignore[attr-defined]
            "OFF",
        )
        assert "› put IO 128 off" in results_text(app)
        assert "IO128: ON → OFF  S_OK  read back OFF ✓" in results_text(app)


async def test_space_in_a_read_only_console_is_refused_and_nothing_is_sent(
    tmp_path: Path,
) -> None:
    app = make_app(tmp_path, read_only=True)
    async with app.run_test(size=SIZE) as pilot:
        tap = FrameTap(tmp_path)
        await watch(pilot, "watch IO 128", 1)
        await pilot.press("f6", "space")
        await until(pilot, lambda: "PUT IO128 refused" in results_text(app), "the refusal")
        assert puts(tap) == []
        assert not app.main_screen.members.toggles.busy(
            next(iter(app.main_screen.members.rows))
        )  # free again: it never went out


async def test_space_on_a_row_that_is_not_io_sends_nothing(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        tap = FrameTap(tmp_path)
        await watch(pilot, "watch I 0", 1)
        await pilot.press("f6", "space")
        message = "Space toggles an IO bit: I0 is not an IO row; nothing sent"
        await until(pilot, lambda: message in results_text(app), "the message")
        assert puts(tap) == []


async def test_a_second_space_before_the_first_came_back_is_ignored(tmp_path: Path) -> None:
    """Each Space toggles from the value shown; a second one before the row shows the
    first one's effect would write OFF again (or a value nobody meant), so it is refused
    until the write is read back. Polling paused: only the read-back can show it."""
    with SimulatorThread() as sim:
        valve = Valve(sim.host, sim.port)
        try:
            # The write stays in flight while the valve holds the simulator's answers (a
            # long timeout: the test says how long, not a clock that load can outrun).
            app = make_app(tmp_path, sim.host, valve.port, timeout=60)
            await _a_second_space_is_ignored(app, valve, tmp_path)
        finally:
            valve.close()


async def _a_second_space_is_ignored(app: RacConsoleApp, valve: Valve, tmp_path: Path) -> None:
    async with app.run_test(size=SIZE) as pilot:
        tap = FrameTap(tmp_path)
        await watch(pilot, "watch IO 128", 1)
        await type_line(pilot, "pause")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.paused,
            "the pause",
        )
        await pilot.press("f6")
        await until(pilot, lambda: app.focused is app.main_screen.panes.table, "the table's focus")
        valve.shut()  # the controller's answers held: the write stays in flight
        await pilot.press("space", "space")  # the second before the first came back
        refusal = "IO128: the last toggle has not come back yet"
        await until(pilot, lambda: refusal in results_text(app), "the refusal")
        await until(pilot, lambda: len(puts(tap)) == 1, "the write sent")
        valve.open()
        done = "IO128: ON → OFF  S_OK  read back OFF ✓"
        await until(pilot, lambda: done in results_text(app), "the first one's reply")
        assert puts(tap) == [b"PUT:RC8:128:IO:11,0\r"]
        await until(  # the read-back shows the row its value, polling paused
            pilot,
            lambda: app.main_screen.panes.table.get_cell("IO128", "value").plain.strip() == "OFF",  # type: ignore[attr-defined]
            "OFF",
        )
        var = next(iter(app.main_screen.members.rows))
        await until(
            pilot, lambda: not app.main_screen.members.toggles.busy(var), "the toggle to come back"
        )
        await pilot.press("space")
        await until(pilot, lambda: len(puts(tap)) == 2, "the second toggle")
        assert puts(tap)[1] == b"PUT:RC8:128:IO:11,-1\r"
        await until(
            pilot,
            lambda: app.main_screen.panes.table.get_cell("IO128", "value").plain.strip() == "ON",  # type: ignore[attr-defined]
            "ON",
        )


async def test_delete_unwatches_the_row_under_the_cursor(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await watch(pilot, "watch IO 128-131", 4)
        await pilot.press("f6", "down", "delete")
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 3, "the row to go")
        assert keys(app) == ["IO128", "IO130", "IO131"]
        assert "› unwatch IO 129" in results_text(app)
        assert cursor(app) == "IO130"  # the row that took its place


async def test_filter_narrows_rows_keeps_the_cursor_and_esc_restores(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await type_line(pilot, "watch P 1 pick")
        await type_line(pilot, "watch IO 128-131 I 0")
        await watch(pilot, "watch F 0 Temp", 7)
        await pilot.press("f6", "down", "down", "down")
        assert cursor(app) == "IO130"
        await pilot.press("slash")
        assert app.focused is app.main_screen.panes.table_filter
        await pilot.press(*"IO13")
        await until(pilot, lambda: keys(app) == ["IO130", "IO131"], "two rows")
        assert cursor(app) == "IO130"
        assert "2 of 7 rows" in app.main_screen.panes.table.title_text
        assert 'filter "IO13"' in app.main_screen.panes.table.title_text
        await pilot.press("escape")
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 7, "every row back")
        assert cursor(app) == "IO130"
        assert app.focused is app.main_screen.panes.table
        assert "7 rows" in app.main_screen.panes.table.title_text
        await pilot.press("slash", *"temp", "enter")  # a label, any case; Enter keeps it
        await until(pilot, lambda: keys(app) == ["F0"], "the labelled row")
        assert app.focused is app.main_screen.panes.table


async def test_hide_io_works_with_the_filter(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await watch(pilot, "watch P 1 IO 128-129 I 0", 4)
        app.main_screen.panes.table.set_hide_io(True)
        assert keys(app) == ["P1", "I0"]
        assert "2 of 4 rows (IO hidden)" in app.main_screen.panes.table.title_text
        app.main_screen.panes.table.set_filter("p")
        assert keys(app) == ["P1"]
        app.main_screen.panes.table.set_hide_io(False)
        assert keys(app) == ["P1"]
        app.main_screen.panes.table.set_filter("")
        assert keys(app) == ["P1", "IO128", "IO129", "I0"]


async def test_s_cycles_the_sort_and_the_cursor_follows_its_variable(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await watch(pilot, "watch P 1 IO 128 I 0 F 1", 4)
        await pilot.press("f6", "down", "down")
        assert cursor(app) == "I0"
        await pilot.press("s")
        assert keys(app) == ["F1", "I0", "IO128", "P1"]
        assert "sort: name" in app.main_screen.panes.table.title_text
        assert cursor(app) == "I0"
        await pilot.press("s")
        assert "sort: last change" in app.main_screen.panes.table.title_text
        # I0 counts at 10 Hz in the simulator: it is always the newest change.
        await until(pilot, lambda: keys(app)[0] == "I0", "the moving row first")
        assert cursor(app) == "I0"
        await pilot.press("s")
        assert keys(app) == ["P1", "IO128", "I0", "F1"]
        assert "sort: as added" in app.main_screen.panes.table.title_text


async def test_trend_cells_and_f_cycles_a_positions_field(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await watch(pilot, "watch P 1 IO 128 S 1", 3)
        await until(
            pilot,
            lambda: "█" in app.main_screen.panes.table.get_cell("IO128", "trend").plain,  # type: ignore[attr-defined]
            "the IO trend",
        )
        assert app.main_screen.panes.table.get_cell("P1", "trend").plain.startswith("X ")  # type: ignore[attr-defined]
        assert app.main_screen.panes.table.get_cell("S1", "trend").plain == ""  # type: ignore[attr-defined]
        await pilot.press("f6", "f")
        await until(
            pilot,
            lambda: app.main_screen.panes.table.get_cell("P1", "trend").plain.startswith("Y "),  # type: ignore[attr-defined]
            "field Y",
        )


async def test_trend_view_of_a_moving_value(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await watch(pilot, "watch I 0 counter", 1)
        await pilot.press("f6", "t")
        view = app.query_one(TrendView)
        assert view.display and app.focused is app.main_screen.panes.table  # t, T, d go on
        assert not app.main_screen.panes.frame_log.display
        var = next(iter(app.main_screen.members.rows))

        def figures() -> str:
            return str(view.stats.render())

        await until(
            pilot,
            lambda: app.main_screen.members.trends.window(var, 0, 10).count >= 4,
            "four samples",
        )
        await pilot.press("f2")  # pause, so the figures hold still to be compared
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.paused,
            "the pause",
        )
        await pilot.pause(0.3)
        window = app.main_screen.members.trends.window(var, 0, view.window)
        numbers = [v for v in window.values if v is not None]
        assert window.low == min(numbers) < window.high == max(numbers) == window.last  # type: ignore[operator]
        await until(pilot, lambda: figures().startswith(f"last {window.last:g}"), "the figures")
        text = figures()
        assert f"min {window.low:g}" in text and f"max {window.high:g}" in text
        # Seconds of samples in a 10 s window: the header says so, and the bars are
        # blank over the part not polled yet instead of stretched over the width.
        assert window.covered < 10
        assert f"10 s  ·  {span_text(window.covered)} of data  ·  {window.count} samples" in text
        lines = view.bars.lines()
        width = view.bars.size.width
        assert len(lines) == view.bars.size.height >= 2 and width > 40
        blank = width - math.ceil(window.covered / 10 * width) - 1
        assert all(line[:blank].isspace() for line in lines)
        assert any(not line[-1].isspace() for line in lines)  # the newest slice drawn
        assert "Trend I0" in str(view.border_title)
        await pilot.press("f6")  # the view's own keys
        assert app.focused is view
        await pilot.press("w")
        await until(pilot, lambda: "1 min" in figures(), "the 1 min window")
        await pilot.press("w", "w")
        assert view.window == 10
        await pilot.press("t")
        assert not view.display and app.main_screen.panes.frame_log.display
        assert app.focused is app.main_screen.panes.table
        await pilot.press("t", "escape")
        assert not view.display and app.focused is app.main_screen.panes.table


async def test_a_command_typed_while_the_table_has_focus_goes_to_the_command_line(
    tmp_path: Path,
) -> None:
    """Typing `get IO 5` with the table focused must not open a trend (`t`) nor toggle
    the bit under the cursor (the space): the letters go to the command line."""
    app = make_app(tmp_path)
    tap = FrameTap(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await watch(pilot, "watch IO 128-129", 2)
        await pilot.press("f6")
        assert app.focused is app.main_screen.panes.table
        for key in [*"get IO 5", "enter"]:  # queued at once, as a fast typist's
            app.simulate_key(key)
        await until(pilot, lambda: "IO5 = " in results_text(app), "the get's answer")
        assert "› get IO 5" in results_text(app)
        assert app.focused is app.main_screen.panes.command_line
        assert not app.query_one(TrendView).display
        assert not any(frame.startswith(b"PUT:") for frame in tap.sent)


async def test_keys_right_after_f6_go_to_the_new_pane(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await watch(pilot, "watch I 1-3", 3)
        for key in ("f6", "down", "down"):  # queued at once, as a fast typist's
            app.simulate_key(key)
        await until(
            pilot, lambda: app.main_screen.panes.table.cursor_row == 2, "the cursor two rows down"
        )
        assert app.main_screen.panes.command_line.value == ""  # no history recalled by the downs
