"""The console does exactly what was typed, and shows only what is true.

Pilot tests against the real simulator (or a hostile server written here) over
loopback. Bursts are key events handed to the driver with no wait in between, as
a paste or a slow ssh link delivers them.
"""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
from textual import events
from textual.pilot import Pilot

from rac_console.tui.app import RacConsoleApp
from rac_console.tui.command_line import CommandLine
from rac_console.tui.frame_log import FrameLog
from rac_console.tui.status_bar import StatusBar
from tests.support.drivers import FrameTap, log_text, make_app, results_text, type_line, until
from tests.support.servers import CLOSE, Answering, RecordingServer

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow


def burst(pilot: Pilot, text: str) -> None:
    """Every key of ``text`` (``\\n`` is Enter) posted at once: nothing awaited between."""
    driver = pilot.app._driver
    assert driver is not None
    for char in text:
        key = events.Key("enter", "\r") if char == "\n" else events.Key(_key_name(char), char)
        key.set_sender(pilot.app)
        driver.send_message(key)


def _key_name(char: str) -> str:
    if char == " ":
        return "space"
    if char.isalnum():
        return char
    from textual.keys import _character_to_key

    return _character_to_key(char)


def connected(app: RacConsoleApp) -> bool:
    return app.main_screen.status is not None and app.main_screen.status.connection == "connected"


def sent_lines(tap: FrameTap) -> list[bytes]:
    return [data.rstrip(b"\r") for data in tap.sent if not data.startswith(b"GET:RC8:0:")]


async def test_a_burst_of_typed_lines_runs_each_line_once_in_order(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        tap = FrameTap(tmp_path)
        await until(
            pilot,
            lambda: (
                app.main_screen.status is not None
                and app.main_screen.status.connection == "connected"
            ),
            "the first connection",
        )
        burst(pilot, "put I 10 1\n5\nget I 1\nget I 2\nget I 3\n")
        await until(pilot, lambda: len(tap.sent) >= 6, "the burst to run")
        await until(pilot, lambda: "I3 = " in results_text(app), "the last line's result")
        assert sent_lines(tap) == [
            b"GET:RC8:10:I:",  # the value before
            b"PUT:RC8:10:I:3,1",
            b"GET:RC8:10:I:",  # read back
            b"GET:RC8:1:I:",
            b"GET:RC8:2:I:",
            b"GET:RC8:3:I:",
        ]
        results = results_text(app)
        assert "unknown command '5'" in results  # the stray "5" ran alone, as typed
        assert results.index("› put I 10 1") < results.index("› 5") < results.index("› get I 1")
        assert app.query_one(CommandLine).value == ""


async def test_a_pasted_block_runs_each_line_once_in_order(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        tap = FrameTap(tmp_path)
        pilot.app.query_one(CommandLine).post_message(
            events.Paste("get I 1\nget I 2\r\nput I 10 7\nget I")
        )
        await until(
            pilot, lambda: "→ 7  S_OK  read back 7 ✓" in results_text(app), "the pasted lines"
        )
        assert sent_lines(tap) == [
            b"GET:RC8:1:I:",
            b"GET:RC8:2:I:",
            b"GET:RC8:10:I:",
            b"PUT:RC8:10:I:3,7",
            b"GET:RC8:10:I:",
        ]
        assert app.query_one(CommandLine).value == "get I"  # the unfinished line, to edit


async def test_a_line_typed_right_after_enter_is_kept(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        tap = FrameTap(tmp_path)
        burst(pilot, "get I 4\nget I 5")  # the second line is typed, not yet entered
        await until(pilot, lambda: "I4 = " in results_text(app), "the first line's result")
        await until(pilot, lambda: app.query_one(CommandLine).value == "get I 5", "the line kept")
        await pilot.press("enter")
        await until(pilot, lambda: "I5 = " in results_text(app), "the second line's result")
        assert sent_lines(tap) == [b"GET:RC8:4:I:", b"GET:RC8:5:I:"]


async def test_the_frame_log_follows_after_layout_changes(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        log = app.query_one(FrameLog)
        for n in range(30):
            await type_line(pilot, f"get I {n}")
        await until(pilot, lambda: "I29 = " in results_text(app), "the gets")
        await until(pilot, lambda: log.line_count >= 60, "the frames in the log")
        # The palette open and shut, a resize that shrinks the log, Tab candidates
        # left on screen (they take the log's rows): each moved the log off its end.
        await pilot.press("ctrl+p")
        await until(pilot, lambda: len(app.screen_stack) > 1, "the command palette")
        await pilot.press("escape")
        await until(pilot, lambda: len(app.screen_stack) == 1, "the palette to close")
        await pilot.resize_terminal(80, 24)
        await until(pilot, lambda: tuple(app.size) == (80, 24), "the resize")
        await type_line(pilot, "get ", enter=False, keys=True)
        await pilot.press("tab")
        await until(
            pilot, lambda: app.main_screen.panes.completions.has_class("-visible"), "the candidates"
        )
        await pilot.press("ctrl+u")
        for n in range(30, 60):
            await type_line(pilot, f"get I {n}")
        await until(pilot, lambda: "I59 = " in results_text(app), "more gets")
        await until(pilot, lambda: "GET:RC8:59:I:" in log_text(app), "the last frame")
        await until(pilot, lambda: log.scroll_y >= log.max_scroll_y, "the log to follow")
        assert "FROZEN" not in str(log.border_title)
        await pilot.press("f4")
        assert "FROZEN" in str(log.border_title)
        frozen_at = log.scroll_y
        for n in range(3):
            await type_line(pilot, f"get S {n + 1}")
        await until(pilot, lambda: log.max_scroll_y > frozen_at, "frames past the view")
        await until(pilot, lambda: "GET:RC8:3:S:" in log_text(app), "the last frame written")
        assert log.scroll_y == frozen_at


def silent_server(answer: bytes | None = None) -> tuple[RecordingServer, Answering]:
    """A server that answers every request with ``answering.answer`` (None: silence,
    CLOSE: close the connection), which a test may change while it runs."""
    answering = Answering(answer)
    return RecordingServer(answering), answering


async def test_per_request_failures_are_marked_in_the_frame_log(tmp_path: Path) -> None:
    server, answering = silent_server()
    try:
        app = make_app(tmp_path, "127.0.0.1", server.port, timeout=0.3)
        async with app.run_test(size=(120, 40)) as pilot:
            await type_line(pilot, "get I 1")
            await until(pilot, lambda: "no reply within 0.3 s" in log_text(app), "a timeout mark")
            answering.answer = b"\xff\x1bgarbage\r"
            await type_line(pilot, "get I 2")
            await until(pilot, lambda: "session reset" in log_text(app), "a bad-reply mark")
            assert log_text(app).count("──") >= 2
            answering.answer = CLOSE
            await type_line(pilot, "get I 3")
            await until(
                pilot, lambda: "closed the connection" in log_text(app), "a dropped-connection mark"
            )
    finally:
        server.close()


async def test_status_line_shows_a_request_waiting_and_no_stale_figures(tmp_path: Path) -> None:
    answer = threading.Event()  # cleared: the controller holds its reply until the test says
    answer.set()

    def reply(line: bytes) -> bytes:
        answer.wait(60)
        return b"0,3,1\r"

    server = RecordingServer(reply)
    try:
        # A long timeout: the request waits as long as the test holds the reply, however
        # slowly a busy machine lets the status line be drawn and read.
        app = make_app(tmp_path, "127.0.0.1", server.port, timeout=60)
        async with app.run_test(size=(160, 40)) as pilot:
            status = app.query_one(StatusBar)
            await type_line(pilot, "get I 1")
            await until(pilot, lambda: "I1 = 1" in results_text(app), "the first reply")
            await until(pilot, lambda: " ms" in str(status.render()), "a round-trip time")
            answer.clear()  # the controller goes quiet
            await type_line(pilot, "get I 2")
            await until(
                pilot, lambda: "waiting for a reply" in str(status.render()), "a waiting request"
            )
            answer.set()
            await until(pilot, lambda: "I2 = 1" in results_text(app), "the late reply")
            await type_line(pilot, "disconnect")
            await until(pilot, lambda: "disconnected" in str(status.render()), "disconnected")
            text = str(status.render())
            assert "waiting" not in text
            assert " ms" not in text  # no round trip of a connection that is gone
    finally:
        answer.set()
        server.close()


async def test_status_line_never_says_not_met_with_interval_zero(tmp_path: Path) -> None:
    app = make_app(tmp_path, interval=0)
    async with app.run_test(size=(160, 40)) as pilot:
        status = app.query_one(StatusBar)
        await type_line(pilot, "watch I 1-20")
        await until(pilot, lambda: "polls/s" in str(status.render()), "polling figures")
        shown: set[str] = set()
        while len(shown) < 5:  # five different status lines while polling flat out
            await until(pilot, lambda: str(status.render()) not in shown, "a new status line")
            shown.add(str(status.render()))
        assert not [line for line in shown if "NOT MET" in line]
        await type_line(pilot, "disconnect")
        await until(pilot, lambda: "disconnected" in str(status.render()), "disconnected")
        text = str(status.render())
        assert "polls/s" not in text and "cycle" not in text


async def test_controller_text_reaches_the_results_pane_escaped(tmp_path: Path) -> None:
    server, answering = silent_server(b"0,8,\x1b]0;pwned\x07 \x1b[2J bell\x07 bs\x08 :V: :smile:\r")
    try:
        app = make_app(tmp_path, "127.0.0.1", server.port)
        async with app.run_test(size=(160, 40)) as pilot:
            await type_line(pilot, "send GET:RC8:1:S:")
            await type_line(pilot, "get S 2")
            await until(pilot, lambda: "S2 = " in results_text(app), "the replies")
            answering.answer = b"\x1b]0;garbled\x07\r"
            await type_line(pilot, "get I 3")
            await until(pilot, lambda: "bad reply" in results_text(app), "the garbled reply")
            answering.answer = b"0,4,1\x9b31m\r"  # the C1 CSI byte
            await type_line(pilot, "get F 4")
            await until(pilot, lambda: "\\x9b31m" in results_text(app), "the C1 reply, escaped")
            shown = results_text(app) + log_text(app)
            for control in ("\x1b", "\x07", "\x08", "\x9b"):
                assert control not in shown
            assert results_text(app).count("\\x1b]0;pwned\\x07") >= 2
            assert ":V: :smile:" in results_text(app)
    finally:
        server.close()


async def test_watch_table_shows_numbers_as_get_does(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        from rac_console.tui.watch_table import WatchTable

        table = app.query_one(WatchTable)
        puts = (
            "put D 1 0.000123",
            "put D 2 1e300",
            "put F 3 -3.3e38",
            "put P 4 .5 1e-5 -3.3e38 0 0 0 -1",
        )
        for line in puts:
            await type_line(pilot, line)
        for line in ("get D 1", "get D 2", "get F 3", "get P 4"):
            await type_line(pilot, line)
        await until(pilot, lambda: "P4 = " in results_text(app), "the gets")
        await type_line(pilot, "watch D 1-2")
        await type_line(pilot, "watch F 3")
        await until(pilot, lambda: table.row_count == 3, "three rows")

        def cell(key: str, column: str) -> str:
            value = table.get_cell(key, column)
            return getattr(value, "plain", str(value)).strip()

        await until(pilot, lambda: cell("F3", "status") == "OK", "the polls")
        results = results_text(app)
        assert cell("D1", "value") == "0.000123" and "D1 = 0.000123" in results
        assert cell("D2", "value") == "1e+300" and "D2 = 1e+300" in results
        assert cell("F3", "value") == "-3.3e+38" and "F3 = -3.3e+38" in results
        assert "X 0.5  Y 1e-05  Z -3.3e+38  Rx 0  Ry 0  Rz 0  Fig -1" in results
        assert cell("F3", "type") == "VT_R4"
        # Every column, VARTYPE last, still fits a 120-column screen.
        widths = [column.get_render_width(table) for column in table.columns.values()]
        assert sum(widths) <= 118, widths


async def test_argument_hint_and_history_suggestion_are_both_shown(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        from textual.widgets import Static

        command_line = app.query_one(CommandLine)
        hint_line = app.query_one("#hint", Static)
        await type_line(pilot, "put P 10 1 2 3 4 5 6 -1")
        await until(pilot, lambda: "P10: " in results_text(app), "the put")
        await type_line(pilot, "put P 10 ", enter=False, keys=True)
        await until(
            pilot,
            lambda: command_line._suggestion == "put P 10 1 2 3 4 5 6 -1",
            "the history suggestion",
        )
        await until(pilot, lambda: hint_line.display, "the hint line")
        assert "X Y Z Rx Ry Rz Fig" in str(hint_line.render())
        await pilot.press("ctrl+u")
        await until(pilot, lambda: not hint_line.display, "the hint line to go")
        await type_line(pilot, "put J 1 ", enter=False, keys=True)  # no history: hint inline
        await until(pilot, lambda: command_line._suggestion.endswith("J7 J8"), "the inline hint")
        assert not hint_line.display


async def test_a_cut_candidate_list_says_how_many_more(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        from rac_console.engine.commands.builtin import BUILTIN
        from rac_console.present.completion import WHOLE_LIST

        await type_line(pilot, "help ", enter=False, keys=True)  # 19 commands: cut
        await pilot.press("tab")
        panel = app.main_screen.panes.completions
        await until(pilot, lambda: panel.has_class("-visible"), "the candidates")
        listed = str(panel.render())
        shown = [line for line in listed.splitlines() if line.strip()]
        more = len(BUILTIN.names()) - (WHOLE_LIST - 1)  # the 9 types would be listed whole
        assert f"… and {more} more" in listed
        assert len(shown) <= panel.region.height
