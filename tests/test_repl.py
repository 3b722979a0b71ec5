"""The line REPL driven through prompt-toolkit's pipe input against the real simulator."""

from __future__ import annotations

import asyncio
import io
import json
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from prompt_toolkit.document import Document
from prompt_toolkit.input import create_pipe_input
from prompt_toolkit.output import DummyOutput
from tui_helpers import WIRE_RECORD, FrameTap

from rac_console.engine import Engine
from rac_console.present.history import History
from rac_console.present.render import make_console
from rac_console.repl.prompt_parts import RacCompleter
from rac_console.repl.repl import Repl

UP = "\x1b[A"


def completions(text: str, seen: set[tuple[str, int]] | None = None) -> list[tuple[str, str]]:
    completer = RacCompleter(lambda: seen or set())
    return [
        (c.text, c.display_meta_text)
        for c in completer.get_completions(Document(text, len(text)), None)
    ]


def test_completer_offers_candidates_with_help() -> None:
    assert ("get", "read a variable") in completions("g")
    assert [text for text, _ in completions("get i")] == ["I", "IO"]
    assert ("IO", "I/O bit") in completions("watch ")
    assert completions("get P ", {("P", 10), ("P", 2), ("I", 1)}) == [("2", "P2"), ("10", "P10")]
    assert [text for text, _ in completions("put IO 5 o")] == ["on", "off"]
    assert [text for text, _ in completions("unwatch a")] == ["all"]
    assert completions("GET:RC8:1") == []


class Driver:
    """A REPL on a pipe: type lines, read what it printed, wait on conditions."""

    def __init__(self, tmp_path: Path, host: str | None = None, **engine_options: object) -> None:
        self.out = io.StringIO()
        self.console = make_console(
            file=self.out, force_terminal=True, width=140, color_system=None
        )
        self.tmp_path = tmp_path
        self.engine = self.make_engine(host, **engine_options)
        self.history = History(tmp_path / "history")
        self.tap = FrameTap(tmp_path)  # what really went on the wire (--record)

    def make_engine(self, host: str | None, **options: object) -> Engine:
        options.setdefault("record", str(self.tmp_path / WIRE_RECORD))
        return Engine(host, **options)  # type: ignore[arg-type]

    async def run(self, steps: Callable[[Driver], object]) -> str:
        with create_pipe_input() as pipe:
            self.pipe = pipe
            self.repl = Repl(
                self.engine, self.history, self.console, input=pipe, output=DummyOutput()
            )
            task = asyncio.create_task(self.repl.run())
            await steps(self)  # type: ignore[misc]
            pipe.send_text("quit\r")
            await asyncio.wait_for(task, 5)
        return self.out.getvalue()

    def type(self, text: str) -> None:
        self.pipe.send_text(text)

    async def until(self, predicate: Callable[[str], bool], what: str, timeout: float = 5) -> None:
        deadline = time.monotonic() + timeout
        while not predicate(self.out.getvalue()):
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out waiting for {what}:\n{self.out.getvalue()}")
            await asyncio.sleep(0.02)


async def test_get_put_and_raw_exchanges_against_the_simulator(tmp_path: Path) -> None:
    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type("put I 7 42\r")
        await d.until(lambda out: "I7: 0 → 42  S_OK  read back 42 ✓" in out, "the put")
        d.type("get I[7]\r")
        await d.until(lambda out: "I7 = 42" in out, "the get")
        d.type("GET:RC8:7:I:\r")
        await d.until(lambda out: "0,3,42" in out, "the raw reply")
        d.type("send PUT:RC8:10:11,0\r")
        await d.until(lambda out: "E_INVALIDCOMMAND" in out, "the controller's error")

    out = await driver.run(steps)
    assert "S_OK  VT_I4  42" in out
    assert "invalid command string" in out
    assert driver.tap.sent == [
        b"GET:RC8:7:I:\r",  # the value before
        b"PUT:RC8:7:I:3,42\r",
        b"GET:RC8:7:I:\r",  # read back
        b"GET:RC8:7:I:\r",
        b"GET:RC8:7:I:\r",
        b"PUT:RC8:10:11,0\r",
    ]


async def test_bad_input_is_answered_and_nothing_is_sent(tmp_path: Path) -> None:
    driver = Driver(tmp_path, read_only=True)

    async def steps(d: Driver) -> None:
        for line in ("put P 10 1 2 3", "get X 1", "put IO 3 maybe", "put I 1 5"):
            d.type(line + "\r")
        await d.until(lambda out: "PUT refused" in out, "the read-only refusal")

    out = await driver.run(steps)
    assert "P needs 7 values: X Y Z Rx Ry Rz Fig, got 3" in out
    assert "unknown variable type 'X'" in out
    assert "IO needs on or off" in out
    assert driver.tap.sent == []


async def test_history_is_recalled_in_a_second_session(tmp_path: Path) -> None:
    async def first_steps(d: Driver) -> None:
        d.type("get S 1\r")
        await d.until(lambda out: "S1 = RC8 simulator" in out, "the first get")

    await Driver(tmp_path).run(first_steps)
    second = Driver(tmp_path)

    async def second_steps(d: Driver) -> None:
        d.type(UP + UP + "\r")  # past "quit", to the previous session's get, run again
        await d.until(lambda out: "S1 = RC8 simulator" in out, "the recalled get")

    await second.run(second_steps)
    lines = (tmp_path / "history").read_text().splitlines()
    assert lines == ["get S 1", "quit", "get S 1", "quit"]


async def test_frames_on_echoes_each_frame_with_its_cr(tmp_path: Path) -> None:
    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type("frames on\r")
        d.type("get I 4\r")
        await d.until(lambda out: "I4 = 12" in out, "the get")

    out = await driver.run(steps)
    assert "→ GET:RC8:4:I:↵" in out
    assert "← 0,3,12↵" in out and "S_OK  VT_I4  12" in out


async def test_watch_updates_in_place_until_enter(tmp_path: Path) -> None:
    driver = Driver(tmp_path)

    def counter_values(out: str) -> set[str]:
        return {
            line.split()[-1]
            for line in out.splitlines()
            if line.strip().startswith("I0 ") and "OK" in line
        }

    async def steps(d: Driver) -> None:
        d.type("watch I 0 cycle every 0.05\r")
        await d.until(lambda out: len(counter_values(out)) >= 3, "the counter to move")
        d.type("\r")
        await d.until(lambda out: not d.repl.rows, "the watch to end")
        d.type("get S 1\r")
        await d.until(lambda out: "S1 = RC8 simulator" in out, "the prompt to come back")

    out = await driver.run(steps)
    assert "cycle" in out and "Enter, q or Ctrl-C returns to the prompt" in out


def test_without_a_terminal_it_behaves_like_run(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "--json", "repl"],
        input="put I 5 9\nget I 5\nget X 1\n",
        capture_output=True,
        text=True,
        timeout=30,
    )
    objects = [json.loads(line) for line in result.stdout.splitlines()]
    assert [o["ok"] for o in objects] == [True, True, False]
    assert objects[1]["value"] == 9
    assert result.returncode == 2
    assert "\x1b[" not in result.stdout


async def test_a_lost_connection_is_one_line_and_the_next_command_reconnects(
    tmp_path: Path,
) -> None:
    from rac_console.sim.server import SimulatorServer

    simulator = await SimulatorServer().start()
    port = simulator.port
    driver = Driver(tmp_path)
    driver.engine = driver.make_engine("127.0.0.1", port=port, timeout=0.5)
    prompts: list[str] = []

    async def steps(d: Driver) -> None:
        d.type("get I 1\r")
        await d.until(lambda out: "I1 = 1" in out, "the first get")
        await simulator.stop()
        d.type("get I 1\r")
        await d.until(lambda out: "the next command reconnects" in out, "the lost line")
        repl_prompt = d.repl.prompt_message()
        prompts.append("".join(text for _, text in repl_prompt))
        restarted = await SimulatorServer(port=port).start()
        try:
            d.type("get I 2\r")
            await d.until(lambda out: "I2 = 250" in out, "the reconnected get")
            prompts.append("".join(text for _, text in d.repl.prompt_message()))
        finally:
            await restarted.stop()

    out = await driver.run(steps)
    lost_lines = [line for line in out.splitlines() if "reconnects" in line]
    assert len(lost_lines) == 1 and "127.0.0.1" in lost_lines[0]
    assert prompts == ["not connected> ", f"127.0.0.1:{port}> "]


async def test_latency_inside_the_repl(tmp_path: Path) -> None:
    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type("latency 50 P 1\r")
        await d.until(lambda out: "latency of GET P1, 50 samples" in out, "the summary")

    out = await driver.run(steps)
    assert "p95" in out and "0 errors" in out
    assert len(driver.tap.sent) == 50
