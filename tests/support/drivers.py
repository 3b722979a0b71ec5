"""The front ends as the tests drive them: the console under Pilot, the REPL on a pipe,
the CLI as a subprocess, the engine alone, and the console in a real terminal (tmux, a
pty).

- the console (Pilot): :func:`make_app` (and :func:`console` on a profile,
  :func:`confirm_console` on a target whose writes ask, :func:`answerable` once its
  question takes an answer), :func:`type_line`, :func:`burst`, :func:`until`,
  :func:`results_text`, :func:`log_text`, :class:`FrameTap` (what went on the wire);
  for the snapshots, :func:`watch_then_pause`, :func:`stage` and :func:`hold_still`;
- the REPL: :class:`Driver`, and :class:`Screen`, a model of what a terminal shows;
- the engine alone: :class:`Front`;
- the CLI: :func:`cli`, :func:`one_error_line`, :func:`json_lines`, :func:`profile` (a
  config file's target), :class:`Running` (a command left running);
- real terminals: :class:`Terminal` (tmux), :func:`spawn_console` and
  :func:`read_until` (a pty, POSIX).
"""

from __future__ import annotations

import asyncio
import codecs
import contextlib
import io
import json
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, Literal, Self, cast

import pytest
from prompt_toolkit.data_structures import Size
from prompt_toolkit.input import create_pipe_input
from prompt_toolkit.output import DummyOutput
from prompt_toolkit.output.vt100 import Vt100_Output
from textual import events
from textual.pilot import Pilot
from textual.widgets import DataTable, RichLog, Static

import rac_console.tui.panes as panes_module
from rac_console.commands.outcome import Outcome
from rac_console.commands.policy import TargetProfile, WritePolicy, Writes, parse_allow
from rac_console.engine import Alert, Cycle, Engine, Message, Note, Result, RowView, Status
from rac_console.engine.published.outbox import Batch
from rac_console.engine.setup.where import Where
from rac_console.present.batches import BatchReader
from rac_console.present.history import History
from rac_console.present.render import make_console
from rac_console.repl.repl import Repl
from rac_console.session import Frame
from rac_console.sim.thread import SimulatorThread
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.confirm_screen import ConfirmWriteScreen
from rac_console.tui.frame_log import FrameLog

# ----------------------------------------------------------------- the console (Pilot)

#: The request timeout of the tests' consoles unless a test gives its own: one no busy
#: machine reaches (a reply an in-process simulator sends late is no timeout of the
#: controller's); a test of timeouts says how short it wants them.
REQUEST_TIMEOUT = 30.0


def make_app(
    tmp_path: Path,
    host: str | None = None,
    port: int = 5006,
    *,
    read_only: bool = False,
    interval: float = 0.05,
    timeout: float = REQUEST_TIMEOUT,
    watch_file: str | None = None,
    record: str | None = None,
    where: Where = Where.CONSOLE,
) -> RacConsoleApp:
    """The console on a private history; it records the wire to ``wire.jsonl`` in
    ``tmp_path`` (read by :class:`FrameTap`) unless given another ``record`` file;
    ``where``: a served console (:attr:`Where.SERVED`) or the terminal's."""
    engine = Engine(
        host,
        port,
        timeout=timeout,
        read_only=read_only,
        interval=interval,
        record=record or str(tmp_path / WIRE_RECORD),
        cycles=True,  # as the console's engine: trends are drawn from its cycles
        where=where,
    )
    return RacConsoleApp(engine, History(tmp_path / "history"), watch_file)


WIRE_RECORD = "wire.jsonl"


#: How long :func:`until` lets the app run for what it waits on: only the point where a
#: wait is called hung (a busy machine can take seconds), never a figure a test checks.
DEADLINE = 20.0


async def until(
    pilot: Pilot[Any], predicate: Callable[[], bool], what: str, timeout: float = DEADLINE
) -> None:
    """Let the app run until ``predicate`` holds; fail naming ``what`` after ``timeout``."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await pilot.pause(0.05)


async def type_line(pilot: Pilot[Any], line: str, enter: bool = True, keys: bool = False) -> None:
    """Enter a line as if pasted (``keys=True`` types it key by key), then press Enter."""
    if keys:
        await pilot.press(*line)
    else:
        from rac_console.tui.command_line import CommandLine

        command_line = pilot.app.query_one(CommandLine)
        command_line.insert_text_at_cursor(line)
    if enter:
        await pilot.press("enter")


def log_text(app: RacConsoleApp) -> str:
    """The frame log's lines, as text."""
    return "\n".join(app.main_screen.query_one(FrameLog).lines)


def results_text(app: RacConsoleApp) -> str:
    """The results pane's lines, as text."""
    return "\n".join(strip.text for strip in app.main_screen.query_one("#results", RichLog).lines)


class FrameTap:
    """What really went on the wire: the ``--record`` file the app under test writes."""

    def __init__(self, tmp_path: Path) -> None:
        self.path = tmp_path / WIRE_RECORD

    def _records(self) -> list[dict[str, object]]:
        if not self.path.exists():
            return []
        return [json.loads(line) for line in self.path.read_text().splitlines() if line]

    @property
    def sent(self) -> list[bytes]:
        """Requests as sent (ASCII, CR included): the recorder escapes nothing in them."""
        return [str(r["text"]).encode("ascii") + b"\r" for r in self._records() if r["dir"] == "tx"]


def console(
    tmp_path: Path, profile: TargetProfile | None = None, **options: object
) -> RacConsoleApp:
    """The console on the built-in simulator, or on ``profile`` (as ``-H cell3``), with
    the tests' request timeout (an in-process simulator answering late on a busy machine
    is no timeout of the controller's)."""
    profiles = options.pop("profiles", {profile.name: profile} if profile else {})
    engine = Engine(
        profile.host if profile else None,
        profile.port if profile else 5006,
        timeout=REQUEST_TIMEOUT,
        interval=0.05,
        record=str(tmp_path / WIRE_RECORD),
        cycles=True,
        policy=profile.policy if profile else None,
        profile=profile,
        profiles=profiles,
        **options,  # type: ignore[arg-type]
    )
    return RacConsoleApp(engine, History(tmp_path / "history"))


def confirm_console(
    tmp_path: Path, cell: SimulatorThread, allow: str | None = None
) -> RacConsoleApp:
    """The console on ``cell3``: writes ask first (and only ``allow`` may be written)."""
    rules = (parse_allow(allow),) if allow else None
    policy = WritePolicy(Writes.CONFIRM, rules, "profile cell3")
    profile = TargetProfile("cell3", cell.host, cell.port, "Cell 3", "red", policy)
    engine = Engine(
        cell.host,
        cell.port,
        timeout=REQUEST_TIMEOUT,
        interval=0.05,
        record=str(tmp_path / WIRE_RECORD),
        cycles=True,
        policy=policy,
        profile=profile,
        profiles={"cell3": profile},
    )
    return RacConsoleApp(engine, History(tmp_path / "history"))


def burst(app: RacConsoleApp, text: str) -> None:
    """Keys typed faster than anything answers: all posted before any is handled."""
    for character in text:
        if character == "\r":
            app.post_message(events.Key("enter", "\r"))
        else:
            app.post_message(events.Key(character, character))


def modal(app: RacConsoleApp) -> ConfirmWriteScreen | None:
    """The write's confirm question, when it is up."""
    return app.screen if isinstance(app.screen, ConfirmWriteScreen) else None


#: What the question's keys line shows once a y counts (and never before).
ANSWERABLE = "[y/N]"


def question_keys(screen: ConfirmWriteScreen) -> str:
    """The question's keys line, as shown ("" while the question is still being built,
    or has closed: no keys line to read)."""
    shown = screen.query("#confirm-keys").results(Static)
    return next((str(keys.content) for keys in shown), "")


async def answerable(pilot: Pilot[Any], screen: ConfirmWriteScreen) -> None:
    """Wait until the question says it takes an answer (``[y/N]`` on its keys line):
    a y pressed sooner is one typed ahead, and ignored."""
    await until(pilot, lambda: ANSWERABLE in question_keys(screen), f"{ANSWERABLE} on the question")


async def declined_with_keys_typed_ahead(pilot: Pilot[Any], app: RacConsoleApp) -> None:
    """``put IO 67 on``, Enter, ``y``, Enter in one burst; the question answered No once
    its guard time is over (the ``y`` and Enter were typed ahead of it)."""
    burst(app, "put IO 67 on\ry\r")
    await until(pilot, lambda: modal(app) is not None, "the question")
    screen = modal(app)
    assert screen is not None
    await answerable(pilot, screen)
    await pilot.press("n")


async def connected(pilot: Pilot[Any], app: RacConsoleApp) -> None:
    await until(
        pilot,
        lambda: (
            app.main_screen.status is not None and app.main_screen.status.connection == "connected"
        ),
        "connected",
    )


# --------------------------------------------------- the console staged for a snapshot

STAGED_FRAMES: list[tuple[Literal["tx", "rx"], bytes, float | None]] = [
    ("tx", b"GET:RC8:1:P:\r", None),
    ("rx", b"0,8196,350,0,450,180,0,180,5\r", 0.00031),
    ("tx", b"PUT:RC8:10:IO:11,-1\r", None),
    ("rx", b"0\r", 0.00022),
    ("tx", b"PUT:RC8:10:11,0\r", None),
    ("rx", b"-2147418107\r", 0.00019),
    ("rx", b"\xff\xfe0,3\r", 0.00020),
]


async def watch_then_pause(pilot: Pilot[Any], lines: tuple[str, ...], rows: int) -> None:
    """Watch, wait for every row's first value from the simulator, then pause. Each
    line's rows are in the table before the next line is typed: rows added together
    are scrolled to as one (the first at the top when they do not all fit), so lines
    the app took in one go under load would show another view."""
    app = cast(RacConsoleApp, pilot.app)
    table = app.main_screen.panes.table
    for line in lines:
        grown = more_rows_than(table, table.row_count)
        await type_line(pilot, line)
        await until(pilot, grown, f"the rows of {line!r}")
    await rows_read(pilot, rows)
    await pause_polling(pilot)


def more_rows_than(table: DataTable[Any], rows: int) -> Callable[[], bool]:
    return lambda: table.row_count > rows


async def rows_read(pilot: Pilot[Any], rows: int) -> None:
    """Wait until the table holds ``rows`` rows, each with its first value read."""
    app = cast(RacConsoleApp, pilot.app)
    await until(
        pilot,
        lambda: (
            len(app.main_screen.members.rows) == rows
            and all(v.status == "OK" for v in app.main_screen.members.rows.values())
        ),
        "every row's first value",
    )


async def pause_polling(pilot: Pilot[Any]) -> None:
    """Type ``pause`` and wait until the status says polling is paused."""
    app = cast(RacConsoleApp, pilot.app)
    await type_line(pilot, "pause")
    await until(
        pilot,
        lambda: app.main_screen.status is not None and app.main_screen.status.paused,
        "the pause",
    )


def stage(app: RacConsoleApp) -> float:
    """Fix what moves with the clock: ages, the round trip, one row timed out. Returns
    the moment the ages count from (see :func:`hold_still`)."""
    now = time.monotonic()
    for n, (var, view) in enumerate(list(app.main_screen.members.rows.items())):
        view = replace(view, changed_at=now - 5.5)
        if n == 2:
            view = replace(view, status="TIMEOUT", stale=True)
        app.main_screen.members.rows[var] = view
    assert app.main_screen.status is not None
    app.main_screen.members.status = replace(app.main_screen.status, rtt=0.00025)
    app.main_screen.panes.frame_log.clear()
    for n, (direction, data, rtt) in enumerate(STAGED_FRAMES):
        app.main_screen.panes.frame_log.add(
            Frame(1_700_000_000.125 + n * 0.001, direction, data, rtt)
        )
    app.main_screen.panes.command_line.cursor_blink = False
    # The sparklines: as many samples as polling gathered would vary from run to run.
    app.main_screen.members.trends.clear()
    samples = tuple((var, view.variant) for var, view in app.main_screen.members.rows.items())
    assert app.main_screen.status is not None
    target = app.main_screen.status.target_id  # the cycles of the target on screen
    for n in range(20):
        app.main_screen.feed.take_cycle(
            None, Cycle(1_700_000_000 + n / 2, 1000 + n / 2, samples, target)
        )
    return now


class HeldClock:
    """``time`` as the console's app module sees it, with ``monotonic()`` held at one
    moment (the rest is the real module)."""

    def __init__(self, now: float) -> None:
        self.now = now

    def monotonic(self) -> float:
        return self.now

    def __getattr__(self, name: str) -> Any:
        return getattr(time, name)


def hold_still(
    app: RacConsoleApp, monkeypatch: pytest.MonkeyPatch, now: float, frames_per_second: float
) -> None:
    """After :func:`stage`, until the screenshot: the table's clock held at ``now`` (the
    ages stay what stage() made them, "5s", however long the screenshot takes to come),
    and the log's rate staged (it counts the staged frames over however many refresh
    ticks the machine managed meanwhile: 3 or 4 frames/s as the load has it)."""
    monkeypatch.setattr(panes_module, "time", HeldClock(now))
    monkeypatch.setattr(app.main_screen, "frames_per_second", lambda: frames_per_second)


# ---------------------------------------------------------------------------- the REPL


class Driver:
    """A REPL on a pipe: type lines, read what it printed, wait on conditions.

    With ``screen``, prompt-toolkit draws its prompt, menus and toolbar into the same
    stream the results are printed to (a 40 x 140 terminal), as on a real terminal."""

    def __init__(
        self,
        tmp_path: Path,
        host: str | None = None,
        *,
        screen: bool = False,
        **engine_options: object,
    ) -> None:
        self.out = io.StringIO()
        self.screen = screen
        self.console = make_console(
            file=self.out, force_terminal=True, width=140, color_system=None
        )
        self.tmp_path = tmp_path
        self.engine = self.make_engine(host, **engine_options)
        self.history = History(tmp_path / "history")
        self.tap = FrameTap(tmp_path)  # what really went on the wire (--record)
        #: Live watches (a table until Enter) that have ended: their key reader gone, so
        #: what is typed next goes to the prompt, not to a watch that reads every key.
        self.watches_begun = self.watches_ended = 0

    def make_engine(self, host: str | None, **options: object) -> Engine:
        options.setdefault("record", str(self.tmp_path / WIRE_RECORD))
        return Engine(host, **options)  # type: ignore[arg-type]

    async def run(self, steps: Callable[[Self], Awaitable[object]]) -> str:
        with create_pipe_input() as pipe:
            self.pipe = pipe
            output = (
                Vt100_Output(
                    self.out, lambda: Size(rows=40, columns=140), term="xterm", enable_cpr=False
                )
                if self.screen
                else DummyOutput()
            )
            self.repl = Repl(self.engine, self.history, self.console, input=pipe, output=output)
            live_watch = self.repl.live_watch

            async def counted(*args: Any) -> None:
                self.watches_begun += 1
                try:
                    await live_watch(*args)
                finally:
                    self.watches_ended += 1

            self.repl.live_watch = counted  # type: ignore[method-assign, assignment]
            task = asyncio.create_task(self.repl.run())
            await steps(self)
            pipe.send_text("quit\r")
            await asyncio.wait_for(task, 5)
        return self.out.getvalue()

    def type(self, text: str) -> None:
        self.pipe.send_text(text)

    def mark(self) -> int:
        """Where the output is now: :meth:`answerable` reads what comes after it."""
        return len(self.out.getvalue())

    async def answerable(self, since: int) -> None:
        """Wait until a question drawn after ``since`` says it takes an answer
        (``[y/N]`` where ``…`` stood): a yes sooner is asked again. Needs ``screen``."""
        assert self.screen, "the question is drawn only on a screen"
        await self.until(lambda out: ANSWERABLE in out[since:], f"{ANSWERABLE} on the question")

    async def until(self, predicate: Callable[[str], bool], what: str, timeout: float = 30) -> None:
        deadline = time.monotonic() + timeout
        while not predicate(self.out.getvalue()):
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out waiting for {what}:\n{self.out.getvalue()}")
            await asyncio.sleep(0.02)


_CSI = re.compile(r"\x1b\[([0-9;?]*)([@-~])")
_OSC = re.compile(r"\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)")
_OTHER_ESCAPE = re.compile(r"\x1b[()][0-9A-Za-z]|\x1b[=>78]")


class Screen:
    """A small model of a terminal screen, to see what a user would see of a byte
    stream.

    It knows what prompt-toolkit and rich write when drawing a prompt or a line: text,
    CR, LF (with the CR a tty adds), backspace, and the CSI sequences that move the
    cursor (A B C D G H) or erase (J K); colours, modes and titles change nothing here.
    The screen grows downwards without scrolling, so every line ever written stays."""

    def __init__(self, width: int) -> None:
        self.width = width
        self.rows: list[list[str]] = [[]]
        self.row = 0
        self.col = 0

    def feed(self, text: str) -> Screen:
        """Play ``text`` onto the screen (one call or many: the same screen)."""
        at = 0
        while at < len(text):
            char = text[at]
            if char == "\x1b":
                for pattern in (_CSI, _OSC, _OTHER_ESCAPE):
                    match = pattern.match(text, at)
                    if match:
                        if pattern is _CSI:
                            self._csi(match.group(1), match.group(2))
                        at = match.end()
                        break
                else:
                    at += 1  # a lone ESC: nothing drawn
                continue
            if char == "\r":
                self.col = 0
            elif char == "\n":  # the tty's ONLCR: a new line starts at column 0
                self._move(self.row + 1, 0)
            elif char == "\b":
                self.col = max(0, self.col - 1)
            elif char >= " ":
                self._put(char)
            at += 1
        return self

    def lines(self) -> list[str]:
        """Every line, trailing blanks taken off."""
        return ["".join(row).rstrip() for row in self.rows]

    def _put(self, char: str) -> None:
        if self.col >= self.width:  # autowrap
            self._move(self.row + 1, 0)
        line = self.rows[self.row]
        if len(line) <= self.col:
            line.extend(" " * (self.col + 1 - len(line)))
        line[self.col] = char
        self.col += 1

    def _move(self, row: int, col: int) -> None:
        self.row, self.col = max(0, row), max(0, min(col, self.width))
        while len(self.rows) <= self.row:
            self.rows.append([])

    def _csi(self, params: str, final: str) -> None:
        if params.startswith("?"):
            return  # private modes: cursor shown or hidden, bracketed paste, ...
        numbers = [int(p) if p else 0 for p in params.split(";")] if params else []
        n = numbers[0] if numbers and numbers[0] else 1
        if final == "A":
            self._move(self.row - n, self.col)
        elif final == "B":
            self._move(self.row + n, self.col)
        elif final == "C":
            self._move(self.row, self.col + n)
        elif final == "D":
            self._move(self.row, self.col - n)
        elif final == "G":
            self._move(self.row, n - 1)
        elif final in "Hf":
            row = numbers[0] if numbers and numbers[0] else 1
            col = numbers[1] if len(numbers) > 1 and numbers[1] else 1
            self._move(row - 1, col - 1)
        elif final == "J":
            mode = numbers[0] if numbers else 0
            if mode == 0:
                del self.rows[self.row][self.col :]
                del self.rows[self.row + 1 :]
            elif mode in (2, 3):
                self.rows = [[] for _ in self.rows]
        elif final == "K":
            mode = numbers[0] if numbers else 0
            line = self.rows[self.row]
            if mode == 0:
                del line[self.col :]
            elif mode == 1:
                line[: self.col] = [" "] * min(self.col, len(line))
            else:
                line.clear()


# -------------------------------------------------------------------- the engine alone

#: How long :meth:`Front.until` waits: only the point where a wait is called hung.
FRONT_DEADLINE = 10.0


class Front(BatchReader):
    """A front end in miniature: drains the outbox and keeps what a screen would show
    (read as every front end reads it)."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self.results: dict[int, Result] = {}
        self.rows: dict[str, RowView] = {}
        self.frames: list[Frame] = []
        self.notes: list[str] = []
        self.alerts: list[str] = []
        self.status: Status | None = None

    def drain(self) -> None:
        self.read("engine", self.engine.outbox.drain())

    def take_status(self, target: str, status: Status) -> None:
        self.status = status

    def take_rows(self, target: str, batch: Batch) -> None:
        for var in batch.removed:
            self.rows.pop(str(var), None)
        self.rows.update({str(var): view for var, view in batch.rows.items()})

    def take_result(self, target: str | None, result: Result) -> None:
        self.results[result.seq] = result

    def take_frame(self, target: str | None, frame: Frame) -> None:
        self.frames.append(frame)

    def take_note(self, target: str | None, note: Note) -> None:
        self.notes.append(note.text)

    def take_alert(self, target: str | None, alert: Alert) -> None:
        self.alerts.append(alert.text)

    def until(self, predicate: Callable[[], bool], what: str) -> None:
        deadline = time.monotonic() + FRONT_DEADLINE
        while True:
            self.drain()
            if predicate():
                return
            assert time.monotonic() < deadline, f"timed out waiting for {what}"
            time.sleep(0.01)

    def run(self, line: str) -> list[str]:
        """Submit a line and wait for its result: the texts of its feedback."""
        seq = self.engine.submit(line)
        self.until(lambda: seq in self.results, f"the answer to {line!r}")
        return [getattr(f, "text", None) or str(f) for f in self.results[seq].feedback]

    def outcome(self, line: str) -> Outcome:
        """Submit an exchange's line and wait for its one outcome."""
        seq = self.engine.submit(line)
        self.until(lambda: seq in self.results, f"the answer to {line!r}")
        (outcome,) = self.results[seq].feedback
        assert isinstance(outcome, Outcome), outcome
        return outcome

    def errors(self, line: str) -> list[str]:
        seq = self.engine.submit(line)
        self.until(lambda: seq in self.results, f"the answer to {line!r}")
        return [
            f.text
            for f in self.results[seq].feedback
            if isinstance(f, Message) and f.level == "error"
        ]

    def sent(self) -> list[bytes]:
        return [f.data for f in self.frames if f.direction == "tx"]


# ----------------------------------------------------------------------------- the CLI


def cli(
    env: dict[str, str], *args: str, stdin: str = "", timeout: float = 20
) -> subprocess.CompletedProcess[str]:
    """``rac-console ARGS`` run to its end, in ``env`` (the fixture), ``stdin`` fed to it."""
    return subprocess.run(
        [sys.executable, "-m", "rac_console", *args],
        env=env,
        input=stdin,
        capture_output=True,
        text=True,
        encoding="utf-8",
        errors="backslashreplace",
        timeout=timeout,
    )


def one_error_line(result: subprocess.CompletedProcess[str]) -> str:
    """The stderr of a failed command: exactly one line, no traceback."""
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip("\n").split("\n")
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rac-console: ")
    return lines[0]


def json_lines(stdout: str) -> list[dict[str, Any]]:
    """The objects of ``--json`` output, one a line."""
    return [json.loads(line) for line in stdout.splitlines() if line.strip()]


def profile(name: str, port: int, extra: str = "", host: str = "127.0.0.1") -> str:
    """A config file's ``[target.NAME]`` (for the ``config`` fixture), ``extra`` lines added."""
    return f'[target.{name}]\nhost = "{host}"\nport = {port}\n{extra}\n'


#: The CLI, as :class:`Running` starts it unless told another program.
RAC = (sys.executable, "-m", "rac_console")


class Running:
    """A CLI command left running: its stdout and stderr lines as they come."""

    def __init__(
        self,
        environment: dict[str, str],
        *args: str,
        wrap: Sequence[str] = (),
        program: Sequence[str] = RAC,
        cwd: Path | None = None,
        err_rate: int | None = None,
    ) -> None:
        """``program`` with ``args``, behind ``wrap`` when given (``ip netns exec B``:
        a command that runs it in place of itself, so that a signal reaches it), in
        ``cwd`` when given; its stderr read at ``err_rate`` bytes a second when given
        (a terminal or an ssh link that does not keep up)."""
        self.process = subprocess.Popen(
            [*wrap, *program, *args],
            env=environment,
            cwd=cwd,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            encoding="utf-8",
            errors="backslashreplace",
        )
        self.out: list[str] = []
        self.err: list[str] = []
        self._lines: queue.Queue[None] = queue.Queue()
        self._lock = threading.Lock()
        threading.Thread(
            target=self._read, args=(self.process.stdout, self.out), daemon=True
        ).start()
        if err_rate is None:
            reading = threading.Thread(target=self._read, args=(self.process.stderr, self.err))
        else:
            reading = threading.Thread(target=self._read_slowly, args=(err_rate,))
        reading.daemon = True
        reading.start()

    def _read(self, stream: object, kept: list[str]) -> None:
        for line in stream:  # type: ignore[attr-defined]
            with self._lock:
                kept.append(line.rstrip("\n"))
            self._lines.put(None)

    def _read_slowly(self, rate: int) -> None:
        """stderr, a tenth of ``rate`` bytes every tenth of a second, split into lines."""
        stream = self.process.stderr
        assert stream is not None
        decoder = codecs.getincrementaldecoder("utf-8")("backslashreplace")
        pending = ""
        while chunk := stream.buffer.read1(max(1, rate // 10)):  # type: ignore[attr-defined]
            pending += decoder.decode(chunk)
            *lines, pending = pending.split("\n")
            with self._lock:
                self.err.extend(lines)
            if lines:
                self._lines.put(None)
            time.sleep(0.1)
        if pending:
            with self._lock:
                self.err.append(pending)
        self._lines.put(None)

    def wait_for(self, what: str, holds: Callable[[], bool], deadline: float = 20) -> None:
        until = time.monotonic() + deadline
        while True:
            with self._lock:
                if holds():
                    return
            left = until - time.monotonic()
            if left <= 0 or (self.process.poll() is not None and self._lines.empty()):
                with self._lock:
                    if holds():
                        return
                raise AssertionError(f"timed out waiting for {what}:\n{self.out[-5:]}\n{self.err}")
            with contextlib.suppress(queue.Empty):
                self._lines.get(timeout=min(left, 0.5))

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                return self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
        return self.process.wait(20)


# ---------------------------------------------------------------------- real terminals

#: How long :meth:`Terminal.until` waits for a text on the screen.
TERMINAL_DEADLINE = 30.0


class Terminal:
    """A tmux server of its own, its environment private to the test."""

    def __init__(self, home: Path) -> None:
        self.socket = f"rac-ascii-{os.getpid()}-{id(self)}"
        self.env = {
            key: value for key, value in os.environ.items() if key not in ("COLUMNS", "LINES")
        }
        self.env.update(
            HOME=str(home),
            XDG_CONFIG_HOME=str(home / "config"),
            XDG_STATE_HOME=str(home / "state"),
            TERM="xterm-256color",
            LANG="C.UTF-8",
        )

    def tmux(self, *words: str) -> str:
        result = subprocess.run(
            ["tmux", "-L", self.socket, *words],
            env=self.env,
            capture_output=True,
            text=True,
            timeout=20,
        )
        return result.stdout

    def start(self, ascii_mode: bool) -> None:
        flag = "RAC_CONSOLE_ASCII=1" if ascii_mode else "RAC_CONSOLE_ASCII=0"
        command = f"env {flag} {sys.executable} -m rac_console"
        self.tmux("new-session", "-d", "-s", "t", "-x", "100", "-y", "30", command)

    def screen(self) -> str:
        return self.tmux("capture-pane", "-p", "-t", "t")

    def until(self, text: str) -> str:
        end = time.monotonic() + TERMINAL_DEADLINE
        while True:
            screen = self.screen()
            if text in screen:
                return screen
            assert time.monotonic() < end, f"{text!r} not on the screen:\n{screen}"
            time.sleep(0.1)

    def close(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True, timeout=20)


def spawn_console(
    home: Path, preexec: Callable[[], None] | None = None
) -> tuple[int, subprocess.Popen[bytes]]:
    """``rac-console`` on the built-in simulator in a 120x40 pty, its files under
    ``home``: the pty's master side and the process."""
    import pty  # POSIX: the tests that use it skip elsewhere

    env = os.environ | {
        "HOME": str(home),
        "XDG_STATE_HOME": str(home),
        "XDG_CONFIG_HOME": str(home),
        "TERM": "xterm-256color",
        "COLUMNS": "120",
        "LINES": "40",
    }
    master, slave = pty.openpty()
    process = subprocess.Popen(
        [sys.executable, "-m", "rac_console"],
        stdin=slave,
        stdout=slave,
        stderr=slave,
        env=env,
        close_fds=True,
        preexec_fn=preexec,
    )
    os.close(slave)
    return master, process


def read_until(
    master: int,
    done: Callable[[bytes], bool],
    deadline: float,
    seen_chunk: Callable[[bytes], None] = lambda seen: None,
) -> bytes:
    """What the console wrote until ``done(everything so far)`` (AssertionError with
    its last output after ``deadline`` seconds); ``seen_chunk`` sees it after each read.
    A terminal that hangs up ends the reading."""
    import select

    seen = b""
    started = time.monotonic()
    while not done(seen):
        assert time.monotonic() - started < deadline, seen[-2000:]
        ready, _, _ = select.select([master], [], [], 0.2)
        if not ready:
            continue
        try:
            seen += os.read(master, 65536)
        except OSError:
            break
        seen_chunk(seen)
    return seen


def stop(process: subprocess.Popen[bytes]) -> None:
    """End the console, killing it if it does not end."""
    if process.poll() is None:
        process.terminate()
    try:
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(timeout=10)
