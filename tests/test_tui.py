"""The Textual console driven with Pilot against the real simulator over loopback."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rac_console.sim.server import SimulatorServer
from rac_console.tui.command_line import CommandLine
from rac_console.tui.status_bar import StatusBar
from rac_console.tui.watch_table import WatchTable
from tests.support.drivers import FrameTap, log_text, make_app, results_text, type_line, until

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow


async def test_starts_on_the_simulator_and_says_so(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await until(
            pilot, lambda: "SIMULATOR" in str(app.query_one(StatusBar).render()), "the status line"
        )
        assert "built-in RC8 simulator" in results_text(app)
        assert app.focused is app.query_one(CommandLine)


async def test_typed_get_put_raw_and_send_show_frames_and_decoding(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        tap = FrameTap(tmp_path)
        await type_line(pilot, "put I 7 42")
        await until(pilot, lambda: "← 0↵" in log_text(app), "the PUT reply in the log")
        await type_line(pilot, "get I[7]")
        await until(pilot, lambda: "S_OK  VT_I4  42" in log_text(app), "the GET decoding")
        await type_line(pilot, "GET:RC8:7:I:")
        await type_line(pilot, "send hello")
        await until(pilot, lambda: "E_INVALIDCOMMAND" in log_text(app), "the send reply")
        log = log_text(app)
        assert "→ PUT:RC8:7:I:3,42↵" in log
        assert "→ GET:RC8:7:I:↵" in log
        assert "→ hello↵" in log
        assert tap.sent == [
            *(
                b"GET:RC8:7:I:\r",
                b"PUT:RC8:7:I:3,42\r",
                b"GET:RC8:7:I:\r",
            ),  # read, write, read back
            *(b"GET:RC8:7:I:\r", b"GET:RC8:7:I:\r", b"hello\r"),
        ]
        await until(pilot, lambda: "I7 = 42" in results_text(app), "the decoded result")
        assert "E_INVALIDCOMMAND" in results_text(app)


async def test_bad_input_is_answered_in_place_and_nothing_is_sent(tmp_path: Path) -> None:
    app = make_app(tmp_path, read_only=True)
    async with app.run_test(size=(120, 40)) as pilot:
        tap = FrameTap(tmp_path)
        for line in (
            "put P 10 1 2 3",
            "get X 1",
            "put I 1 abc",
            "frob",
            "put I 1 5",
            "PUT:RC8:1:I:3,5",
        ):
            await type_line(pilot, line)
        await until(
            pilot,
            lambda: len(re.findall(r"PUT (I1 )?refused", results_text(app))) == 2,
            "read-only",
        )
        text = results_text(app)
        assert "P needs 7 values: X Y Z Rx Ry Rz Fig, got 3" in text
        assert "unknown variable type 'X'" in text
        assert "I needs a whole number" in text
        assert "unknown command 'frob'" in text
        assert tap.sent == []
        assert "→" not in log_text(app)


async def test_watch_rows_appear_and_change_over_time(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(160, 40)) as pilot:
        table = app.query_one(WatchTable)
        await type_line(pilot, "watch I 0 cycle counter")
        await type_line(pilot, "watch P 1")
        await type_line(pilot, "watch IO 128-131")
        await until(pilot, lambda: table.row_count == 6, "six rows")

        def cell(key: str, column: str) -> str:
            value = table.get_cell(key, column)
            return getattr(value, "plain", str(value))

        await until(pilot, lambda: cell("I0", "status") == "OK", "the first poll")
        first = cell("I0", "value")
        await until(pilot, lambda: cell("I0", "value") != first, "the counter to move")
        assert cell("I0", "label") == "cycle counter"
        assert "X" in cell("P1", "value") and "Fig" in cell("P1", "value")
        assert cell("P1", "value").split()[:2] == ["X", "350"]  # as get shows it
        assert cell("IO128", "value").strip() == "ON" and cell("IO129", "value").strip() == "OFF"
        assert cell("P1", "type") == "VT_R4|VT_ARRAY"
        await type_line(pilot, "unwatch IO 128-131")
        await until(pilot, lambda: table.row_count == 2, "the IO rows to go")


async def test_history_is_recalled_after_a_restart(tmp_path: Path) -> None:
    first = make_app(tmp_path)
    async with first.run_test() as pilot:
        await type_line(pilot, "get S 1")
        await type_line(pilot, "get S 1")  # a repeat is stored once
        await type_line(pilot, "get I 2")
        await until(pilot, lambda: "I2 = " in results_text(first), "the commands to run")
    second = make_app(tmp_path)
    async with second.run_test() as pilot:
        command_line = second.query_one(CommandLine)
        await pilot.press("up")
        assert command_line.value == "get I 2"
        await pilot.press("up")
        assert command_line.value == "get S 1"
        await pilot.press("up")
        assert command_line.value == "get S 1"  # oldest entry: stays
        await pilot.press("down", "down")
        assert command_line.value == ""
    assert (tmp_path / "history").read_text().splitlines() == ["get S 1", "get I 2"]


async def test_tab_completes_and_lists_candidates_with_help(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        command_line = app.query_one(CommandLine)
        await type_line(pilot, "wat", enter=False, keys=True)
        await pilot.press("tab")
        assert command_line.value == "watch "
        await type_line(pilot, "i", enter=False, keys=True)
        await pilot.press("tab")
        panel = app.main_screen.panes.completions
        assert panel.has_class("-visible")
        listed = str(panel.render())
        assert "I " in listed and "integer" in listed and "IO" in listed and "I/O bit" in listed
        await pilot.press("ctrl+u")
        await type_line(pilot, "put P 10 ", enter=False, keys=True)
        await until(
            pilot,
            lambda: command_line._suggestion.endswith("X Y Z Rx Ry Rz Fig"),
            "the argument hint",
        )
        await pilot.press("right")  # a hint is never inserted
        assert command_line.value == "put P 10 "


async def test_lost_connection_marks_rows_stale_and_recovers(tmp_path: Path) -> None:
    simulator = await SimulatorServer().start()
    port = simulator.port
    app = make_app(tmp_path, "127.0.0.1", port, timeout=0.5)
    async with app.run_test(size=(120, 40)) as pilot:
        table = app.query_one(WatchTable)
        await type_line(pilot, "watch I 3")

        def status() -> str:
            return table.get_cell("I3", "status").plain if table.row_count else ""  # type: ignore[attr-defined]

        await until(pilot, lambda: status() == "OK", "the first poll")
        assert "LIVE 127.0.0.1" in str(app.query_one(StatusBar).render())
        await simulator.stop()
        await until(pilot, lambda: "stale" in status(), "the row to go stale")
        await until(
            pilot,
            lambda: "lost, retrying" in str(app.query_one(StatusBar).render()),
            "the status line to say lost",
        )
        assert table.get_cell("I3", "value").plain.strip() == "3"  # type: ignore[attr-defined]  # last good value kept
        assert "connection lost" in log_text(app)
        restarted = await SimulatorServer(port=port).start()
        try:
            await until(pilot, lambda: status() == "OK", "polling to resume")
            # The log's note may come a batch after the row: waited for, not assumed.
            await until(pilot, lambda: "reconnected" in log_text(app), "the log says so")
        finally:
            await restarted.stop()


async def test_a_label_is_shown_as_typed_never_as_markup(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 30)) as pilot:
        await type_line(pilot, "watch I 1 [/x] [red]tool")
        table = app.query_one(WatchTable)
        await until(pilot, lambda: table.row_count == 1, "the row")
        assert table.get_cell("I1", "label").plain == "[/x] [red]tool"  # type: ignore[attr-defined]
        assert app.is_running and "watching I1" in results_text(app)
