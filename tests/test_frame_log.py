"""The frame log as serial-terminal users expect it: hex view, gaps, filter (issue 13.5).

The pure parts (gap text, hex text, the filter's matching, the gap's highlight) are
tested alone; the keys with Pilot against the built-in simulator.
"""

from __future__ import annotations

import gc
import re
from pathlib import Path
from typing import cast

import pytest
from rich.segment import Segment
from textual.pilot import Pilot

from rac_console.present.filtering import FrameFilter
from rac_console.present.frames import gap_text, hex_text
from rac_console.protocol import parse_request, parse_response
from rac_console.session import Frame
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.frame_lines import FrameHighlighter
from rac_console.tui.frame_log import KEPT_BYTES, KEPT_OTHERS, FrameLog
from tests.support.drivers import log_text, make_app, results_text, type_line, until

SIZE = (150, 40)
#: A frame line: the time, the gap since the previous frame, the arrow.
GAP_LINE = re.compile(r"^\d\d:\d\d:\d\d\.\d{3} +\+\d+(?:\.\d+)?(?:ms|s) [→←] ")


# ------------------------------------------------------------------ pure parts


@pytest.mark.parametrize(
    ("seconds", "text"),
    [
        (0.0, "+0.00ms"),
        (0.00021, "+0.21ms"),
        (0.0123, "+12.3ms"),
        (0.0999, "+99.9ms"),
        (0.09999, " +100ms"),
        (0.5, " +500ms"),
        (1.5, "+1.500s"),
        (12.5, "+12.50s"),
        (125.0, "+125.0s"),
        (5000.0, " +5000s"),
        (-0.001, "+0.00ms"),  # the wall clock stepped back: no negative gap
    ],
)
def test_gap_text_is_fixed_width_with_its_unit(seconds: float, text: str) -> None:
    assert gap_text(seconds) == text
    assert len(gap_text(seconds)) >= 7


def test_gap_text_of_the_first_frame_is_blank() -> None:
    assert gap_text(None) == " " * 7


def test_hex_text_is_every_byte_cr_included() -> None:
    assert hex_text(b"GET:RC8:1:I:\r") == "47 45 54 3a 52 43 38 3a 31 3a 49 3a 0d"
    assert hex_text(b"\x1b\x9b0\r") == "1b 9b 30 0d"


@pytest.mark.parametrize(
    ("data", "var"),
    [
        (b"GET:RC8:128:IO:\r", ("IO", 128)),
        (b"PUT:RC8:10:I:5\r", ("I", 10)),
        (b"get:rc8:3:p:\r", ("P", 3)),
        (b"GET:RC8:1:X:\r", None),
        (b"HELLO\r", None),
        (b"\xff\r", None),
    ],
)
def test_a_request_line_names_its_variable(data: bytes, var: tuple[str, int] | None) -> None:
    parsed = parse_request(data).var
    assert (None if parsed is None else (parsed[0].code, parsed[1])) == var


def test_filter_by_variable_matches_its_requests_and_their_replies() -> None:
    io = FrameFilter.of("IO128")
    assert io.var == ("IO", 128)
    assert io.matches(parse_request(b"GET:RC8:128:IO:\r"), "→ GET:RC8:128:IO:↵")
    # a reply: by its request
    assert io.matches(parse_request(b"GET:RC8:128:IO:\r"), "← 0,11,-1↵   S_OK")
    assert not io.matches(parse_request(b"GET:RC8:12:IO:\r"), "→ GET:RC8:12:IO:↵")
    assert not io.matches(None, "← 0,11,-1↵")  # a reply nobody asked for
    assert FrameFilter.of("I 10").var == ("I", 10)
    assert FrameFilter.of("P[3]").var == ("P", 3)
    assert FrameFilter.of(" io 128 ").var == ("IO", 128)


def test_filter_by_text_matches_the_line_any_case() -> None:
    text = FrameFilter.of("invalidcommand")
    assert text.var is None
    assert text.matches(parse_request(b"FOO\r"), "← -2147418107↵   E_INVALIDCOMMAND 0x...")
    assert not text.matches(parse_request(b"FOO\r"), "→ FOO↵")
    assert FrameFilter.of("S_OK").var is None
    assert not FrameFilter.of("")  # no filter: everything passes
    assert FrameFilter.of("  ").matches(None, "anything")


def spans(text: str, slow_after: float = 1.0) -> dict[str, str]:
    highlighter = FrameHighlighter()
    highlighter.slow_after = slow_after
    from rich.text import Text

    styled = highlighter(Text(text))
    return {styled.plain[s.start : s.end]: str(s.style) for s in styled.spans}


def test_a_slow_reply_gap_is_highlighted_and_a_short_one_dim() -> None:
    slow = spans("12:00:00.000 +1.500s ← 0↵   S_OK")
    assert "reverse" in slow["+1.500s"] or "on " in slow["+1.500s"]
    quick = spans("12:00:00.000 +0.21ms ← 0↵   S_OK")
    assert quick["+0.21ms"] == "dim"
    idle = spans("12:00:00.000 +1.500s → GET:RC8:1:I:↵")  # before a request: idle time
    assert idle["+1.500s"] == "dim"


# ------------------------------------------------------------------- the keys


def frame_lines(app: RacConsoleApp) -> list[str]:
    return [
        line for line in app.main_screen.panes.frame_log.lines if " → " in line or " ← " in line
    ]


async def get(pilot: Pilot, line: str, result: str) -> None:
    app = cast(RacConsoleApp, pilot.app)
    await type_line(pilot, line)
    await until(pilot, lambda: result in results_text(app), f"the result of {line}")


async def focus_log(pilot: Pilot) -> None:
    app = pilot.app
    assert isinstance(app, RacConsoleApp)
    await pilot.press("f6", "f6")
    assert app.focused is app.main_screen.panes.frame_log


@pytest.mark.slow
async def test_hex_view_shows_the_bytes_of_frames_already_shown_and_new(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await get(pilot, "get I 1", "I1 = ")
        await until(pilot, lambda: "GET:RC8:1:I:" in log_text(app), "the frame")
        assert "47 45 54" not in log_text(app)
        await pilot.press("f7")
        assert app.main_screen.panes.frame_log.hex_view
        assert "hex" in app.main_screen.panes.frame_log.title_text
        get_i1 = "47 45 54 3a 52 43 38 3a 31 3a 49 3a 0d"
        await until(pilot, lambda: get_i1 in log_text(app), "the hex of a frame shown before")
        line = next(line for line in app.main_screen.panes.frame_log.lines if get_i1 in line)
        assert "→ GET:RC8:1:I:↵" in line  # beside its text, at this width
        await get(pilot, "get I 2", "I2 = ")
        await until(pilot, lambda: "3a 32 3a 49 3a 0d" in log_text(app), "the hex of a new frame")
        await pilot.press("f7")
        assert not app.main_screen.panes.frame_log.hex_view
        await until(pilot, lambda: "47 45 54" not in log_text(app), "the hex gone")
        assert "GET:RC8:2:I:" in log_text(app)


@pytest.mark.slow
async def test_hex_goes_under_the_text_at_narrow_widths(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(60, 30)) as pilot:
        app.main_screen.panes.frame_log.hex_view = True
        await get(pilot, "get P 1", "P1 = ")
        await until(pilot, lambda: "→ GET:RC8:1:P:↵" in log_text(app), "the frame")
        lines = list(app.main_screen.panes.frame_log.lines)
        at = next(n for n, line in enumerate(lines) if "→ GET:RC8:1:P:↵" in line)
        assert "47 45 54" not in lines[at]
        assert lines[at + 1].lstrip().startswith("47 45 54 3a")
        assert lines[at + 1].startswith(" ")


@pytest.mark.slow
async def test_each_frame_shows_the_time_since_the_previous_one(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await get(pilot, "get I 1", "I1 = ")
        await get(pilot, "get I 2", "I2 = ")
        await until(pilot, lambda: len(frame_lines(app)) >= 4, "the frames")
        lines = frame_lines(app)
        assert all(GAP_LINE.match(line) for line in lines[1:]), lines
        await focus_log(pilot)
        await pilot.press("t")
        assert not app.main_screen.panes.frame_log.show_gaps
        await until(
            pilot,
            lambda: all(re.match(r"^\d\d:\d\d:\d\d\.\d{3} [→←] ", x) for x in frame_lines(app)),
            "the gaps gone from every line",
        )
        app.main_screen.action_toggle_frame_times()
        assert app.main_screen.panes.frame_log.show_gaps


@pytest.mark.slow
async def test_filter_by_variable_keeps_its_frames_and_their_replies(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await type_line(pilot, "watch I 1 I 2")
        await until(pilot, lambda: log_text(app).count("GET:RC8:2:I:") >= 3, "polls of both")
        await type_line(pilot, "pause")
        await until(
            pilot,
            lambda: app.main_screen.status is not None and app.main_screen.status.paused,
            "the pause",
        )
        await get(pilot, "get IO 128", "IO128 = ")
        await type_line(pilot, "send GET:RC8:1:I:")  # a raw line names I1 too
        await until(pilot, lambda: log_text(app).count("GET:RC8:1:I:") >= 4, "the raw line")
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "every frame drawn")
        await focus_log(pilot)
        await pilot.press("slash")
        assert app.focused is app.main_screen.panes.log_filter
        await pilot.press(*"I 1")
        await until(
            pilot,
            lambda: 'filter "I 1"' in app.main_screen.panes.frame_log.title_text,
            "the filter",
        )
        lines = frame_lines(app)
        assert lines
        for request, reply in zip(lines[::2], lines[1::2], strict=True):
            assert "→ GET:RC8:1:I:↵" in request
            assert "← 0," in reply  # each request followed by its reply
        count = re.search(r"(\d+) of (\d+) frames", app.main_screen.panes.frame_log.title_text)
        assert count is not None
        assert int(count.group(1)) == len(lines) < int(count.group(2))
        await pilot.press("escape")
        assert app.focused is app.main_screen.panes.frame_log
        await until(pilot, lambda: "GET:RC8:2:I:" in log_text(app), "every frame back")
        assert "filter" not in app.main_screen.panes.frame_log.title_text
        assert "GET:RC8:128:IO:" in log_text(app)


@pytest.mark.slow
async def test_filter_by_text_and_poll_frames_stay_f3(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await type_line(pilot, "watch I 1")
        await until(pilot, lambda: log_text(app).count("GET:RC8:1:I:") >= 3, "polls")
        await type_line(pilot, "send FOO")
        await until(pilot, lambda: "E_INVALIDCOMMAND" in log_text(app), "the error reply")
        await focus_log(pilot)
        await pilot.press("slash", *"invalidcommand", "enter")
        assert app.focused is app.main_screen.panes.frame_log
        await until(pilot, lambda: len(frame_lines(app)) == 1, "the one line")
        assert "E_INVALIDCOMMAND" in frame_lines(app)[0]
        assert re.search(r"1 of \d+ frames", app.main_screen.panes.frame_log.title_text)
        app.main_screen.panes.frame_log.set_filter("GET:RC8:1:I:")
        await until(pilot, lambda: len(frame_lines(app)) >= 3, "the polls")
        await pilot.press("f3")  # hides poll frames, the ones shown already too
        await until(pilot, lambda: frame_lines(app) == [], "the polls hidden")
        assert "polls hidden" in app.main_screen.panes.frame_log.title_text
        await pilot.press("f3")
        await until(pilot, lambda: len(frame_lines(app)) >= 3, "the polls back")
        await pilot.press("slash", "escape")
        assert "filter" not in app.main_screen.panes.frame_log.title_text
        await pilot.press("ctrl+l")
        app.main_screen.panes.frame_log.set_filter(
            "FOO"
        )  # cleared means forgotten: nothing to show again
        await pilot.pause()
        assert frame_lines(app) == []
        assert re.search(r"0 of \d+ frames", app.main_screen.panes.frame_log.title_text)


def test_the_log_is_bounded_and_counts_what_it_keeps() -> None:
    log = FrameLog()
    reply = parse_response("0,3,1")
    for n in range(KEPT_OTHERS // 2 + 500):  # more frames than the log keeps
        t = 1_700_000_000 + n / 1000
        request = parse_request(f"GET:RC8:{n % 7}:I:\r".encode())
        log.add(Frame(t, "tx", f"GET:RC8:{n % 7}:I:\r".encode(), request=request))
        log.add(Frame(t + 0.0001, "rx", b"0,3,1\r", 0.0001, response=reply, request=request))
    log.flush()
    assert log.frames_kept == KEPT_OTHERS
    log.set_filter("I 3")
    shown = re.search(r"(\d+) of (\d+) frames", log.title_text)
    assert shown is not None and int(shown.group(2)) == KEPT_OTHERS
    assert abs(int(shown.group(1)) - KEPT_OTHERS / 7) < 4  # a seventh: I3's GETs and replies


def test_frames_as_long_as_a_reply_may_be_are_kept_within_a_budget_of_bytes() -> None:
    """A reply may be 64 KiB: kept by the count alone, 20,000 of them held 1.3 GB. The
    oldest go once the kept frames' bytes pass KEPT_BYTES; the newest stay."""
    log = FrameLog()
    request = parse_request(b"GET:RC8:1:S:\r")
    long_reply = b"0,8," + b"x" * 60_000 + b"\r"
    count = 2 * KEPT_BYTES // len(long_reply)  # twice the budget
    for n in range(count):
        t = 1_700_000_000 + n
        log.add(Frame(t, "tx", b"GET:RC8:1:S:\r", poll=True, request=request))
        log.add(Frame(t + 0.001, "rx", long_reply, 0.001, poll=True, request=request))
    log.flush()
    assert log.frames_kept < count, log.title_text  # of the 2 * count frames given
    assert log.frames_kept * len(long_reply) // 2 <= KEPT_BYTES
    log.add(Frame(1_700_100_000, "tx", b"GET:RC8:7:I:\r", request=parse_request(b"GET:RC8:7:I:\r")))
    log.set_filter("I 7")
    log.flush()
    assert "1 of" in log.title_text  # the newest is kept, beside them


async def test_the_frame_lines_cut_at_the_views_edge_are_not_kept_once_drawn(
    tmp_path: Path,
) -> None:
    """Rich keeps each cut of a text that holds a character outside its single-cell fast
    path (a frame line's ``←``, ``↵``) in a cache of 16,384, never looked up again: every
    frame line too long for the view, once drawn, stayed (9 MB once full, under a flood)."""
    from textual.app import App, ComposeResult

    class Pane(App[None]):
        def compose(self) -> ComposeResult:
            yield FrameLog()

    def cut_lines_alive() -> int:
        gc.collect()
        return sum(isinstance(o, Segment) and "←" in o.text for o in gc.get_objects())

    request = parse_request(b"GET:RC8:0:P:\r")
    app = Pane()
    async with app.run_test(size=(60, 12)) as pilot:
        log = app.query_one(FrameLog)
        await until(pilot, lambda: log.size.height > 0, "the log laid out")

        async def rounds(start: int, count: int) -> None:
            for n in range(start, start + count):  # three new long lines each, drawn
                for m in range(3):
                    t = 1_700_000_000 + n + m / 10
                    reply = f"0,8196,{n}.{m}" + ",300.0000001" * 6 + "\r"
                    log.add(Frame(t, "rx", reply.encode(), 0.001, request=request))
                log.flush()
                await pilot.pause(0.05)

        await rounds(0, 10)
        before = cut_lines_alive()
        await rounds(10, 40)  # 120 lines more, each cut at the view's edge
        assert cut_lines_alive() < before + 40, (before, cut_lines_alive())
