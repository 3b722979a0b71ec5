"""The console on a cell: two or three simulators over real sockets, one engine each.

Rows from every target in one table (a Target column), a badge per target, lines to
the current target or to ``@NAME``, Space and Del on a row going to its target, the
confirm dialog naming the target, the merged frame log filtered by target, trends of
two targets on one time axis; one controller down leaves the others polling.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from textual.pilot import Pilot

from rac_console.protocol import kind_of
from rac_console.sim.cell import SimulatedCellThread
from rac_console.sim.controller import SimulatedController
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.confirm_screen import ConfirmWriteScreen
from tests.support.cells import make_cell_app, row
from tests.support.drivers import answerable, log_text, results_text, type_line, until

#: A console on two or three simulators: a second or more each, seconds on a busy machine.
pytestmark = pytest.mark.slow

#: A quick handshake: robotA's IO 128 on every 0.8 s, robotB's IO 64 0.1 s after it.
QUICK = {"cycle": 0.8, "hold": 0.4, "reaction": 0.1}


@pytest.fixture
def two() -> Iterator[SimulatedCellThread]:
    with SimulatedCellThread(2, **QUICK) as sims:
        yield sims


@pytest.fixture
def three() -> Iterator[SimulatedCellThread]:
    with SimulatedCellThread(3, **QUICK) as sims:
        yield sims


def controller(sims: SimulatedCellThread, index: int) -> SimulatedController:
    found = sims.cell.servers[index].controller
    assert isinstance(found, SimulatedController)
    return found


def value(sims: SimulatedCellThread, index: int, code: str, number: int) -> object:
    return controller(sims, index).value(kind_of(code), number)


async def connected(pilot: Pilot, app: RacConsoleApp) -> None:
    await until(
        pilot,
        lambda: all(
            s.status is not None and s.status.connection == "connected"
            for s in app.main_screen.members.states.values()
        ),
        "every target connected",
    )


async def watch_handshake(pilot: Pilot, app: RacConsoleApp) -> None:
    await type_line(pilot, "@robotA watch IO 128 part placed")
    await type_line(pilot, "@robotB watch IO 64 go")
    await until(
        pilot,
        lambda: row(app, "robotA", "IO128") is not None and row(app, "robotB", "IO64") is not None,
        "a row on each target",
    )


def seen_values(app: RacConsoleApp, name: str, var: str, into: set[object]) -> bool:
    shown = row(app, name, var)
    if shown is not None and shown.variant is not None and not shown.stale:
        into.add(shown.variant.value)
    return len(into) > 1


def table_cells(app: RacConsoleApp) -> list[tuple[str, str]]:
    """(target, variable) of each row of the table, top to bottom."""
    table = app.main_screen.panes.table
    return [
        (str(table.get_row_at(n)[0]).strip(), str(table.get_row_at(n)[1]))
        for n in range(table.row_count)
    ]


async def test_two_targets_rows_of_each_in_one_table(tmp_path: Path, two) -> None:
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await watch_handshake(pilot, app)
        # The same variable on both targets is two rows.
        await type_line(pilot, "watch I 10")
        await type_line(pilot, "@robotB watch I 10")
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 4, "four rows")
        assert table_cells(app) == [
            ("robotA", "IO128"),
            ("robotA", "I10"),
            ("robotB", "IO64"),
            ("robotB", "I10"),
        ]
        a_values: set[object] = set()
        b_values: set[object] = set()
        await until(pilot, lambda: seen_values(app, "robotA", "IO128", a_values), "IO128 moves")
        await until(pilot, lambda: seen_values(app, "robotB", "IO64", b_values), "IO64 moves")
        line = app.main_screen.panes.status_bar.line.plain
        assert "robotA" in line and "robotB" in line and line.count("connected") == 2
        assert "robotA ›" in app.main_screen.panes.prompt.render().plain  # type: ignore[union-attr]
        results = results_text(app)
        assert "robotB › watch I 10" in results  # the result names its target


async def test_a_write_goes_to_the_current_target_or_to_at_name(tmp_path: Path, two) -> None:
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await type_line(pilot, "put I 10 5")  # the current target: robotA
        await until(pilot, lambda: value(two, 0, "I", 10) == 5, "robotA's I10 written")
        await type_line(pilot, "@robotB put I 10 7")
        await until(pilot, lambda: value(two, 1, "I", 10) == 7, "robotB's I10 written")
        assert value(two, 0, "I", 10) == 5
        await until(pilot, lambda: "robotB › put I 10 7" in results_text(app), "the echo")
        assert "robotA › put I 10 5" in results_text(app)
        await pilot.press("f8")  # use the next target: robotB
        await until(pilot, lambda: app.cell.current == "robotB", "robotB current")
        await type_line(pilot, "put I 11 9")
        await until(pilot, lambda: value(two, 1, "I", 11) == 9, "robotB's I11 written")
        assert value(two, 0, "I", 11) != 9
        await until(
            pilot, lambda: "robotB ›" in str(app.main_screen.panes.prompt.render()), "the prompt"
        )


async def test_space_and_del_on_a_row_go_to_its_target(tmp_path: Path, two) -> None:
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await type_line(pilot, "watch IO 20")
        await type_line(pilot, "@robotB watch IO 20")
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 2, "IO20 on each")
        await until(
            pilot,
            lambda: all(
                row(app, n, "IO20") and row(app, n, "IO20").variant  # type: ignore[union-attr]
                for n in app.main_screen.members.states
            ),
            "IO20 read on each",
        )
        before_a = value(two, 0, "IO", 20)
        before_b = value(two, 1, "IO", 20)
        app.main_screen.panes.table.focus()
        await pilot.press("down")  # robotB's row
        await until(
            pilot,
            lambda: app.main_screen.panes.table.cursor_target() == "robotB",
            "the cursor on robotB",
        )
        await pilot.press("space")
        await until(pilot, lambda: value(two, 1, "IO", 20) != before_b, "robotB's IO20 toggled")
        assert value(two, 0, "IO", 20) == before_a
        word = "off" if before_b else "on"
        await until(pilot, lambda: f"robotB › put IO 20 {word}" in results_text(app), "the echo")
        await pilot.press("delete")
        await until(pilot, lambda: row(app, "robotB", "IO20") is None, "robotB's row gone")
        assert row(app, "robotA", "IO20") is not None
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 1, "one row left")


async def test_the_confirm_dialog_names_the_target(tmp_path: Path, two) -> None:
    app = make_cell_app(tmp_path, two, confirm=("robotB",))
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await type_line(pilot, "@robotB put I 10 42")
        await until(pilot, lambda: isinstance(app.screen, ConfirmWriteScreen), "the question")
        screen = app.screen
        assert isinstance(screen, ConfirmWriteScreen)
        assert screen.member == "robotB"
        box = screen.query_one("#confirm-box")
        assert "robotB" in str(box.border_title) and "Cell B" in str(box.border_title)
        await answerable(pilot, screen)
        await pilot.press("y")
        await until(pilot, lambda: value(two, 1, "I", 10) == 42, "robotB's I10 written")
        assert value(two, 0, "I", 10) != 42
        # robotA's writes do not ask.
        await type_line(pilot, "put I 10 41")
        await until(pilot, lambda: value(two, 0, "I", 10) == 41, "robotA's I10 written")
        assert not isinstance(app.screen, ConfirmWriteScreen)


async def test_the_frame_log_names_and_filters_targets(tmp_path: Path, two) -> None:
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await watch_handshake(pilot, app)
        await until(
            pilot,
            lambda: (
                "robotA → GET:RC8:128:IO:" in log_text(app)
                and "robotB → GET:RC8:64:IO:" in log_text(app)
            ),
            "frames of both targets, each named",
        )
        app.main_screen.panes.frame_log.set_filter("@robotB")
        app.main_screen.panes.frame_log.flush()
        await until(pilot, lambda: "GET:RC8:64:IO:" in log_text(app), "robotB's frames")
        frames = [line for line in log_text(app).splitlines() if "→" in line or "←" in line]
        assert frames and all(" robotB " in line for line in frames)
        app.main_screen.panes.frame_log.set_filter("@robotA IO128")
        await until(pilot, lambda: "GET:RC8:128:IO:" in log_text(app), "robotA's IO128")
        frames = [line for line in log_text(app).splitlines() if "→" in line or "←" in line]
        strays = [line for line in frames if " robotA " not in line]
        assert frames and not strays, strays


async def test_trends_of_two_targets_on_one_time_axis(tmp_path: Path, two) -> None:
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await watch_handshake(pilot, app)
        app.main_screen.panes.table.focus()
        await pilot.press("t")  # robotA's IO128
        await until(pilot, lambda: app.main_screen.panes.trend_view.has_class("-open"), "the trend")
        app.main_screen.panes.table.focus()
        await pilot.press("down", "T")  # robotB's IO64 over it
        view = app.main_screen.panes.trend_view
        await until(pilot, lambda: len(view.series) == 2, "two series")
        assert [(t, str(v)) for t, v, _ in view.series] == [("robotA", "IO128"), ("robotB", "IO64")]
        await until(
            pilot,
            lambda: all(
                app.main_screen.members.trend_store(t).window(v, 0, view.window).count >= 4
                for t, v, _ in view.series
            ),
            "samples of both",
        )
        view.redraw()
        lines = view.bars.lines()
        assert any(line.startswith("robotA IO128") for line in lines)
        assert any(line.startswith("robotB IO64") for line in lines)
        assert "robotA IO128 + robotB IO64" in str(view.border_title)


async def test_one_target_down_leaves_the_others_polling(tmp_path: Path, three) -> None:
    app = make_cell_app(tmp_path, three, timeout=0.5)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await type_line(pilot, "@robotA watch IO 128")
        await type_line(pilot, "@robotB watch I 10")
        await type_line(pilot, "@robotC watch I 0")
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 3, "a row on each")
        await until(
            pilot,
            lambda: (shown := row(app, "robotB", "I10")) is not None and shown.variant is not None,
            "robotB's row read",
        )
        three.stop_one(1)  # robotB switched off
        await until(
            pilot,
            lambda: (shown := row(app, "robotB", "I10")) is not None and shown.stale,
            "robotB's row stale",
        )

        def badge_b() -> str:
            return app.main_screen.panes.status_bar.line.plain.split("│")[1]

        await until(pilot, lambda: "connected" not in badge_b(), "robotB's badge not connected")
        assert "robotB" in badge_b()
        b = app.main_screen.members.states["robotB"]
        assert b.status is not None and b.status.connection != "connected"
        assert (
            app.main_screen.panes.status_bar.line.plain.count("connected") == 2
        )  # robotA and robotC are
        a_values: set[object] = set()
        c_values: set[object] = set()
        await until(pilot, lambda: seen_values(app, "robotA", "IO128", a_values), "robotA polls")
        await until(pilot, lambda: seen_values(app, "robotC", "I0", c_values), "robotC polls")
        assert not row(app, "robotA", "IO128").stale  # type: ignore[union-attr]
        assert not row(app, "robotC", "I0").stale  # type: ignore[union-attr]


async def test_completion_offers_the_cell_targets(tmp_path: Path, two) -> None:
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await type_line(pilot, "use robotB", enter=False)
        app.main_screen.panes.command_line.value = "use rob"
        app.main_screen.panes.command_line.cursor_position = len("use rob")
        await pilot.press("tab")
        assert app.main_screen.panes.command_line.value == "use robot"
        app.main_screen.panes.command_line.value = "@robotB wat"
        app.main_screen.panes.command_line.cursor_position = len(
            app.main_screen.panes.command_line.value
        )
        await pilot.press("tab")
        assert app.main_screen.panes.command_line.value == "@robotB watch "


async def test_the_io_grid_takes_the_current_targets_io_rows_only(tmp_path: Path, two) -> None:
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await watch_handshake(pilot, app)
        await pilot.press("f5")  # robotA's IO rows to the grid; robotB's stay in the table
        await until(pilot, lambda: table_cells(app) == [("robotB", "IO64")], "robotB's row only")
        await pilot.press("f8")  # robotB current: its IO goes to the grid, robotA's back
        await until(pilot, lambda: table_cells(app) == [("robotA", "IO128")], "robotA's row only")


async def test_a_cell_of_one_is_the_console_as_before(tmp_path: Path) -> None:
    from rac_console.commands.target import Target
    from rac_console.engine.cell.cell import Cell
    from rac_console.engine.setup.options import EngineOptions
    from rac_console.present.history import History
    from rac_console.sim.thread import SimulatorThread

    with SimulatorThread() as sim:
        options = EngineOptions(interval=0.05, cycles=True)
        cell = Cell([("sim", Target(sim.host, sim.port))], options=options)
        app = RacConsoleApp(cell, History(tmp_path / "history"))
        async with app.run_test(size=(120, 40)) as pilot:
            await connected(pilot, app)
            await type_line(pilot, "watch I 10")
            await until(pilot, lambda: app.main_screen.panes.table.row_count == 1, "the row")
            assert (
                next(str(c.label) for c in app.main_screen.panes.table.columns.values())
                == "Variable"
            )
            assert str(app.main_screen.panes.table.get_row_at(0)[0]) == "I10"
            assert (
                not app.main_screen.panes.prompt.is_mounted
            )  # no prompt: the command line as it was
            assert not app.main_screen.check_action("next_target", ())
            await until(pilot, lambda: "› watch I 10" in results_text(app), "the echo")
            assert "sim ›" not in results_text(app)
            assert (
                "LIVE" in app.main_screen.panes.status_bar.line.plain
            )  # the status line as it was


async def test_T_keeps_the_table_so_the_next_rows_T_joins_the_trend(tmp_path: Path, two) -> None:
    """T on a row opens its trend and leaves the cursor in the table: Down, T, and the
    next row is overlaid, with no key to go back first."""
    app = make_cell_app(tmp_path, two)
    async with app.run_test(size=(120, 40)) as pilot:
        await connected(pilot, app)
        await watch_handshake(pilot, app)
        app.main_screen.panes.table.focus()
        await pilot.press("T")
        await until(pilot, lambda: app.main_screen.panes.trend_view.has_class("-open"), "the trend")
        await pilot.press("down", "T")
        await until(pilot, lambda: len(app.main_screen.panes.trend_view.series) == 2, "two series")
        assert app.focused is app.main_screen.panes.table
