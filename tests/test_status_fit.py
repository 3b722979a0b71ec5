"""The status line fits its width: whole fields in priority order, dropped from the
right, never half a field nor a trailing separator; its badges read (contrast) and stand
apart; and the frame times agree with the round trip the reply carries."""

from __future__ import annotations

import re
import socket
import threading
import time
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest
from rich.cells import cell_len
from rich.color import Color
from rich.text import Text
from textual.geometry import Region

from rac_console.commands.policy import TargetProfile, WritePolicy, Writes
from rac_console.engine import Engine, Status
from rac_console.present import status
from rac_console.present.history import History
from rac_console.present.status import contrast, label_style, status_text
from rac_console.session import Frame
from rac_console.session.blocking import Session
from rac_console.sim.thread import SimulatorThread
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import WIRE_RECORD, until
from tests.support.servers import RecordingServer

LONG_LABEL = "Cell 5 — a rather long label for the welding cell by the door"

BASE = Status(
    target="LIVE 192.168.0.1:5006",
    is_simulator=False,
    has_session=True,
    host="192.168.0.1",
    port=5006,
    timeout=2.0,
    read_only=False,
    connection="connected",
    retry_at=None,
    rtt=0.0076,
    paused=False,
    watched=3,
    interval=0.5,
    period=0.5,
    cycle_seconds=0.007,
    polls_per_second=16.0,
    interval_met=True,
    record_failure=None,
    seen=frozenset(),
    profile="cell5",
    label=LONG_LABEL,
    colour="red",
    writes="confirm",
)
RUNNING = ("put I1 5", 3.2, 2)

#: Each field as it must appear when it appears at all: (a word only it holds, its whole form).
WHOLE = {
    "rtt": r"rtt (\d+\.\d\d ms|–)",
    "retry": r"((lost|dropped early|dropped), )?retry(ing in)? \d+\.\d s( \(backoff\))?",
    "Esc": r" Esc( cancels)?(: put I1 5)? \(3 s\)  \+2( queued)?",
    "cycle": r"cycle \d+ ms/0\.5 s",
    "polls": r"\d+ polls/s",
    "frames": r"\d+ frames/s",
    "CONFIRM": r" CONFIRM WRITES ",
    "LIVE": r" LIVE 192\.168\.0\.1:5006 ",
}


def assert_whole(line: Text, width: int) -> str:
    plain = line.plain
    assert cell_len(plain) <= width, plain
    assert not plain.rstrip().endswith("·"), plain
    assert "· ·" not in plain and "··" not in plain, plain
    for word, form in WHOLE.items():
        if word in plain:
            assert re.search(form, plain), f"{word!r} cut in {plain!r}"
    return plain


@pytest.mark.parametrize("width", [60, 80, 120, 200])
def test_a_long_label_never_hides_the_target_writes_or_connection(width: int) -> None:
    plain = assert_whole(status_text(BASE, None, 120.0, width=width), width)
    assert plain.startswith(" Cell 5")
    assert " LIVE 192.168.0.1:5006 " in plain and " CONFIRM WRITES " in plain
    assert "connected" in plain
    if width >= 120:
        assert "rtt 7.60 ms" in plain
    if width >= 200:
        assert LONG_LABEL not in plain  # the label keeps to its share, even with room
        assert "cycle 7 ms/0.5 s · 16 polls/s · 120 frames/s" in plain


SIMULATED = replace(
    BASE,
    target="SIMULATOR (built-in)",
    is_simulator=True,
    host=None,
    profile=None,
    label=None,
    writes="open",
)


@pytest.mark.parametrize("width", [38, 40, 50])
def test_on_a_small_screen_the_simulator_says_it_is_one_and_connected_whole(width: int) -> None:
    """At 40 columns the line held ``SIMULATOR (built-in)  writes open ·`` and was cut
    there: the connection went, and a separator was left hanging."""
    plain = assert_whole(status_text(SIMULATED, None, 0.0, width=width), width)
    assert "SIMULATOR" in plain and "writes open" in plain and "connected" in plain


@pytest.mark.parametrize("width", [60, 80, 120, 200])
def test_a_retry_keeps_its_countdown(width: int) -> None:
    status = replace(BASE, connection="lost", retry_at=time.monotonic() + 3.0, rtt=None)
    plain = assert_whole(status_text(status, None, 5.0, width=width), width)
    assert re.search(r"lost, retry(ing in)? [23]\.\d s", plain), plain
    if width >= 80:
        assert plain.startswith(" Cell 5")
    assert " LIVE 192.168.0.1:5006 " in plain and " CONFIRM WRITES " in plain


@pytest.mark.parametrize("width", [60, 80, 120, 200])
def test_a_running_line_keeps_esc_and_its_countdown(width: int) -> None:
    plain = assert_whole(status_text(BASE, None, 30.0, running=RUNNING, width=width), width)
    assert "connected" in plain and " CONFIRM WRITES " in plain
    if width >= 80:  # the README's promise: 80 columns never lose the way out
        assert re.search(r" Esc( cancels)?(: put I1 5)? \(3 s\)  \+2", plain), plain
    if width >= 200:
        assert re.search(r" Esc cancels: put I1 5 \(3 s\)  \+2 queued", plain), plain


@pytest.mark.parametrize("width", [60, 80, 120, 200])
def test_a_retry_and_a_running_line_together(width: int) -> None:
    status = replace(BASE, connection="dropped", retry_at=time.monotonic() + 1.5, rtt=None)
    plain = assert_whole(status_text(status, None, 0.0, running=RUNNING, width=width), width)
    assert re.search(r"(dropped( early)?, )?retry(ing in)? \d\.\d s", plain), plain
    assert " LIVE 192.168.0.1:5006 " in plain
    if width >= 80:
        assert re.search(r" Esc( cancels)?(: put I1 5)? \(3 s\)  \+2", plain), plain


def test_fields_are_dropped_lowest_priority_first() -> None:
    full = status_text(BASE, None, 120.0).plain
    for width in range(60, cell_len(full) + 2):
        plain = assert_whole(status_text(BASE, None, 120.0, width=width), width)
        if "frames/s" in plain:
            assert "polls/s" in plain and "rtt" in plain
        if "polls/s" in plain:
            assert "rtt" in plain
    assert status_text(BASE, None, 120.0, width=500).plain == full


def test_without_a_width_the_whole_line_is_built() -> None:
    plain = status_text(replace(BASE, label="Cell 3"), None, 3.0).plain
    assert plain.endswith("· 16 polls/s · 3 frames/s")


# ------------------------------------------------------------ the console, 80x24


@pytest.fixture
def cell() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


@pytest.mark.slow
async def test_the_console_draws_whole_fields_at_80_columns(
    tmp_path: Path, cell: SimulatorThread
) -> None:
    profile = TargetProfile(
        "cell5", cell.host, cell.port, LONG_LABEL, "red", WritePolicy(Writes.CONFIRM)
    )
    engine = Engine(
        cell.host,
        cell.port,
        timeout=1.0,
        interval=0.05,
        record=str(tmp_path / WIRE_RECORD),
        cycles=True,
        policy=profile.policy,
        profile=profile,
        profiles={"cell5": profile},
    )
    app = RacConsoleApp(engine, History(tmp_path / "history"))
    async with app.run_test(size=(80, 24)) as pilot:
        await until(
            pilot,
            lambda: (
                app.main_screen.status is not None
                and app.main_screen.status.connection == "connected"
            ),
            "connected",
        )
        app.main_screen.refresh_table()
        await pilot.pause()
        bar = app.main_screen.panes.status_bar
        drawn = "".join(
            strip.text for strip in bar.render_lines(Region(0, 0, bar.size.width, 1))
        ).strip()
        assert drawn.startswith("Cell 5")
        assert "CONFIRM WRITES" in drawn and "LIVE 127.0.0.1:" in drawn
        assert "connected" in drawn
        assert not drawn.endswith("·") and not drawn.endswith("rtt")
        if "rtt" in drawn:
            assert re.search(r"rtt \d+\.\d\d ms", drawn), drawn
        # A narrower screen: the line is built again for its width, not cut.
        await pilot.resize_terminal(64, 24)
        await pilot.pause()
        narrow = "".join(
            strip.text for strip in bar.render_lines(Region(0, 0, bar.size.width, 1))
        ).strip()
        assert "connected" in narrow and "CONFIRM WRITES" in narrow, narrow


# ------------------------------------------------------------ badge colours


def ink_contrast(colour: str) -> float:
    style = label_style(colour)
    assert style.color is not None and style.bgcolor is not None
    return contrast(style.color, style.bgcolor)


@pytest.mark.parametrize("colour", ["red", "yellow", "#2080ff", "white", "black"])
def test_the_label_ink_is_black_or_white_whichever_reads_best(colour: str) -> None:
    style = label_style(colour)
    assert style.color is not None and style.bgcolor is not None
    ink = style.color.get_truecolor()
    assert ink in ((0, 0, 0), (255, 255, 255))
    other = (255, 255, 255) if ink == (0, 0, 0) else (0, 0, 0)
    background = style.bgcolor
    assert contrast(style.color, background) >= contrast(Color.from_rgb(*other), background)
    assert ink_contrast(colour) >= 4.5
    # Truecolor, so a theme cannot turn the profile's colour into another one.
    assert background.get_truecolor() == Color.parse(colour).get_truecolor()
    assert style.color.triplet is not None and background.triplet is not None


def test_contrast_figures() -> None:
    black, white = Color.parse("#000000"), Color.parse("#ffffff")
    assert contrast(black, white) == pytest.approx(21.0)
    assert contrast(white, white) == pytest.approx(1.0)
    assert contrast(Color.parse("#777777"), white) == pytest.approx(4.48, abs=0.01)


@pytest.mark.parametrize(
    "name",
    ["LIVE", "SIMULATOR", "NO_SESSION", "READ_ONLY", "CONFIRM", "ALARM", "CSV", "RUNNING"],
)
def test_every_badge_reads(name: str) -> None:
    style = getattr(status, f"{name}_STYLE")
    assert style.color.triplet is not None and style.bgcolor.triplet is not None  # truecolor
    assert contrast(style.color, style.bgcolor) >= 4.5


def test_an_unknown_colour_gets_the_default_reversed_block() -> None:
    style = label_style("no_such_colour")
    assert style.reverse and style.bgcolor is None


def test_the_label_target_and_writes_badges_stand_apart() -> None:
    line = status_text(replace(BASE, label="Cell 3"), None, 0.0)

    def style_of(text: str) -> str:
        start = line.plain.index(text)
        return " ".join(str(s.style) for s in line.spans if s.start <= start < s.end)

    label, target, writes = style_of("Cell 3"), style_of("LIVE"), style_of("CONFIRM")
    assert len({label, target, writes}) == 3, (label, target, writes)
    assert line.plain.startswith(" Cell 3   LIVE 192.168.0.1:5006   CONFIRM WRITES ")


# ------------------------------------------------------------ frame times


class HeldAfterSend:
    """The session's socket, whose ``sendall`` comes back only once the reply waits
    to be read: as a sending thread the scheduler (or the GIL) runs again late."""

    def __init__(self, sock: socket.socket) -> None:
        self._sock = sock

    def sendall(self, data: bytes) -> None:
        self._sock.sendall(data)
        import select

        assert select.select((self._sock,), (), (), 5.0)[0], "no reply came"

    def __getattr__(self, name: str) -> object:
        return getattr(self._sock, name)


def slow_answer(line: bytes) -> bytes:
    time.sleep(0.1)  # the controller's own time to answer
    return b"0,3,0\r"


@pytest.mark.parametrize("held", [False, True])
def test_a_frame_is_stamped_when_it_crossed(held: bool) -> None:
    server = RecordingServer(slow_answer)
    frames: list[Frame] = []
    lock = threading.Lock()

    def observe(frame: Frame) -> None:
        with lock:
            frames.append(frame)

    try:
        with Session("127.0.0.1", server.port, timeout=2.0) as session:
            session.add_frame_observer(observe)
            session.connect()
            if held:
                session._sock = HeldAfterSend(session._sock)  # type: ignore[arg-type, assignment]
            reply = session.send_raw("GET:RC8:10:I:")
    finally:
        server.close()
    tx, rx = frames
    assert (tx.direction, rx.direction) == ("tx", "rx")
    assert rx.rtt == reply.rtt and reply.rtt >= 0.08
    assert rx.time > tx.time
    assert rx.time - tx.time >= 0.08
    assert rx.time - tx.time == pytest.approx(reply.rtt, abs=0.02)
