"""The line REPL driven through prompt-toolkit's pipe input against the real simulator."""

from __future__ import annotations

import asyncio
import contextlib
import json
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from prompt_toolkit.buffer import Buffer
from prompt_toolkit.data_structures import Size
from prompt_toolkit.document import Document
from prompt_toolkit.output.vt100 import Vt100_Output

from rac_console.engine import Engine
from rac_console.present.history import History
from rac_console.present.render import make_console
from rac_console.repl.prompt_parts import RacCompleter
from rac_console.repl.repl import Repl
from tests.support.drivers import Driver, Screen

UP = "\x1b[A"


def completions(text: str, seen: set[tuple[str, int]] | None = None) -> list[tuple[str, str]]:
    completer = RacCompleter(lambda: seen or set())
    return [
        (c.text, c.display_meta_text)
        for c in completer.get_completions(Document(text, len(text)), None)  # type: ignore[arg-type]
    ]


def test_completer_offers_candidates_with_help() -> None:
    assert ("get", "read a variable") in completions("g")
    assert [text for text, _ in completions("get i")] == ["I", "IO"]
    assert ("IO", "I/O bit") in completions("watch ")
    assert completions("get P ", {("P", 10), ("P", 2), ("I", 1)}) == [("2", "P2"), ("10", "P10")]
    assert [text for text, _ in completions("put IO 5 o")] == ["on", "off"]
    assert [text for text, _ in completions("unwatch a")] == ["all"]
    assert completions("GET:RC8:1") == []


#: A control sequence of the kind prompt-toolkit draws with (CSI ... letter).
CONTROL_SEQUENCE = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


def visible(text: str) -> str:
    """What a screen shows of ``text``, roughly: the control sequences taken out."""
    return CONTROL_SEQUENCE.sub("", text)


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
        await d.until(lambda out: "PUT I1 refused" in out, "the read-only refusal")

    out = await driver.run(steps)
    assert "P needs 7 values: X Y Z Rx Ry Rz Fig, got 3" in out
    assert "unknown variable type 'X'" in out
    assert "IO needs on or off" in out
    assert driver.tap.sent == []


async def test_history_is_recalled_in_a_second_session(tmp_path: Path) -> None:
    async def first_steps(d: Driver) -> None:
        d.type("get S 1\r")
        await d.until(lambda out: 'S1 = "RC8 simulator"' in out, "the first get")

    await Driver(tmp_path).run(first_steps)
    second = Driver(tmp_path)

    async def second_steps(d: Driver) -> None:
        d.type(UP + UP + "\r")  # past "quit", to the previous session's get, run again
        await d.until(lambda out: 'S1 = "RC8 simulator"' in out, "the recalled get")

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


@pytest.mark.slow  # over half a second
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
        await d.until(lambda out: d.watches_ended == 1, "the watch to end")
        d.type("get S 1\r")
        await d.until(lambda out: 'S1 = "RC8 simulator"' in out, "the prompt to come back")

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
        prompts.append("".join(text for _, text, *_ in repl_prompt))
        restarted = await SimulatorServer(port=port).start()
        try:
            d.type("get I 2\r")
            await d.until(lambda out: "I2 = 250" in out, "the reconnected get")
            prompts.append("".join(text for _, text, *_ in d.repl.prompt_message()))
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


# ------------------------------------------------------------------ issue 20


async def test_tab_lists_the_nine_types_whole(tmp_path: Path) -> None:
    """The menu had room for 7 lines: T and IO were behind a scrollbar."""
    driver = Driver(tmp_path, screen=True)
    helps = ["integer", "single float", "double", "string", "vector", "position", "joints"]
    helps += ["transform", "I/O bit"]

    async def steps(d: Driver) -> None:
        d.type("get \t")
        await d.until(lambda out: "integer" in visible(out), "the menu")
        await d.until(
            lambda _: d.repl.prompt.default_buffer.complete_state is not None, "the menu state"
        )
        d.type("\x15")  # Ctrl-U: the line goes, quit comes next

    out = visible(await driver.run(steps))
    assert [help for help in helps if help not in out] == []


def says(text: str) -> Callable[[str], bool]:
    return lambda out: text in out


async def test_a_refused_line_is_never_suggested_and_never_kept(tmp_path: Path) -> None:
    """A mistyped command (answered with the closest one) and a write refused by
    read-only: Up recalls them in this session, to be fixed; neither is suggested, and
    neither reaches the history file."""
    driver = Driver(tmp_path, read_only=True)

    def buffer_of(d: Driver) -> Buffer:
        return d.repl.prompt.default_buffer

    async def suggested(d: Driver, typed: str) -> str:
        d.type("\x15" + typed)  # Ctrl-U first: each on an empty line
        await d.until(lambda _: buffer_of(d).text == typed, f"{typed!r} typed")
        await d.until(lambda _: buffer_of(d).suggestion is not None, f"a suggestion for {typed}")
        suggestion = buffer_of(d).suggestion
        assert suggestion is not None
        return typed + suggestion.text

    async def steps(d: Driver) -> None:
        for line, answer in (
            ("get S 1", "S1 = "),
            ("pause", "polling paused"),
            ("gte S 1", "unknown command 'gte': did you mean get?"),
            ("put I 1 5", "refused"),
        ):
            d.type(line + "\r")
            await d.until(says(answer), answer)
        assert await suggested(d, "g") == "get S 1"
        assert await suggested(d, "p") == "pause"
        d.type("\x15" + UP)
        await d.until(lambda _: buffer_of(d).text == "put I 1 5", "the refused line recalled")
        d.type("\x15")
        await d.until(lambda _: buffer_of(d).text == "", "the line cleared")

    await driver.run(steps)
    assert (tmp_path / "history").read_text().splitlines() == ["get S 1", "pause", "quit"]


def toolbar_text(driver: Driver) -> str:
    return "".join(text for _, text, *_ in driver.repl.toolbar())


async def test_after_pause_the_toolbar_and_a_watch_say_polling_is_paused(tmp_path: Path) -> None:
    """``watch I 0`` after ``pause`` showed a row that never filled, and nothing said why."""
    driver = Driver(tmp_path)

    def row_line(out: str) -> str:
        rows = [line for line in out.splitlines() if line.strip().startswith("I0 ")]
        return rows[-1] if rows else ""

    async def steps(d: Driver) -> None:
        d.type("pause\r")
        await d.until(lambda out: "polling paused" in out, "the pause")
        assert "POLLING PAUSED" in toolbar_text(d)
        d.type("watch I 0\r")
        await d.until(lambda out: "wait for resume" in out, "the watch saying why")
        await d.until(lambda out: "not polled" in row_line(out), "the row marked not polled")
        assert "paused" in row_line(out=d.out.getvalue())
        d.type("\r")
        await d.until(lambda _: d.watches_ended == 1, "the watch to end")
        d.type("resume\r")
        await d.until(lambda out: "polling resumed" in out, "the resume")
        assert "POLLING PAUSED" not in toolbar_text(d)

    await driver.run(steps)


async def test_on_a_live_controller_the_banner_says_live_with_the_profile(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Only the simulator had a first line; a live target started with a bare prompt."""
    from rac_console.engine.setup.config import CONFIG_ENV, load_config
    from rac_console.sim.thread import SimulatorThread

    with SimulatorThread() as cell:
        config = tmp_path / "config.toml"
        config.write_text(
            f'[target.cell3]\nhost = "{cell.host}"\nport = {cell.port}\n'
            'label = "Cell 3 — welding"\nwrites = "confirm"\n',
            encoding="utf-8",
        )
        monkeypatch.setenv(CONFIG_ENV, str(config))
        profiles = load_config().profiles
        profile = profiles["cell3"]
        driver = Driver(
            tmp_path, profile.host, port=profile.port, policy=profile.policy, profile=profile
        )

        async def steps(d: Driver) -> None:
            await d.until(lambda out: "LIVE" in out, "the banner")

        out = await driver.run(steps)
    first = out.splitlines()[0]
    assert first.startswith(f"LIVE controller {cell.host}:{cell.port}"), first
    assert "profile cell3 (Cell 3 — welding): writes confirm" in first
    assert "sim" not in first.split(":")[0]


async def test_on_a_plain_live_host_the_banner_names_it(tmp_path: Path) -> None:
    from rac_console.sim.thread import SimulatorThread

    with SimulatorThread() as cell:
        driver = Driver(tmp_path, cell.host, port=cell.port)

        async def steps(d: Driver) -> None:
            await d.until(lambda out: "LIVE" in out, "the banner")

        out = await driver.run(steps)
    assert out.splitlines()[0].startswith(f"LIVE controller {cell.host}:{cell.port}.")


async def test_a_line_printed_while_the_prompt_is_up_goes_above_it(tmp_path: Path) -> None:
    """An alert (or a frame, or the first connection's failure) drained while the user
    types was written into the prompt's line: ``sim> get Irecording stopped``."""
    from rac_console.engine import Alert

    driver = Driver(tmp_path, screen=True)

    def screen_lines(out: str) -> list[str]:
        return Screen(140).feed(out).lines()

    async def steps(d: Driver) -> None:
        await d.until(lambda out: "sim>" in screen_lines(out)[-1], "the prompt")
        d.type("get I")
        await d.until(lambda out: screen_lines(out)[-1] == "sim> get I", "the typed text")
        d.engine.outbox.put_many([Alert("recording stopped: disk full")])
        await d.until(lambda out: "disk full" in out, "the alert")
        await d.until(lambda out: screen_lines(out)[-1] == "sim> get I", "the prompt again")
        d.type(" 1\r")
        await d.until(lambda out: "I1 = 1" in out, "the get")

    lines = screen_lines(await driver.run(steps))
    assert "recording stopped: disk full" in lines, lines  # a line of its own
    assert "sim> get I 1" in lines, lines  # the prompt whole, below it
    assert lines.index("recording stopped: disk full") < lines.index("sim> get I 1")


class HeldReply:
    """The server's answers: ``GET I 1`` is held until the test releases it."""

    def __init__(self) -> None:
        self.release = threading.Event()

    def __call__(self, line: bytes) -> bytes:
        if line == b"GET:RC8:1:I:":
            assert self.release.wait(10), "the test never released the reply"
            return b"0,3,1\r"
        return b"0,3,250\r"


@pytest.mark.skipif(sys.platform == "win32", reason="a pseudo-terminal is POSIX")
async def test_keys_typed_ahead_while_a_command_waits_stay_out_of_its_result(
    tmp_path: Path,
) -> None:
    """Issue 20, item 11: under load a result came out as ``get I 2I1 = 1``.

    Between two prompts the terminal was back in cooked mode, so it echoed the keys
    typed ahead where the result was about to be printed. Here on a real
    pseudo-terminal: the controller holds its reply until the next line is typed ahead,
    and what the terminal shows is played onto a model screen.
    """
    import fcntl
    import os
    import pty
    import struct
    import termios

    from prompt_toolkit.input.vt100 import Vt100Input

    from tests.support.servers import RecordingServer

    reply = HeldReply()
    server = RecordingServer(reply)
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
    keys = os.fdopen(slave, "r", closefd=False)
    screen_file = os.fdopen(os.dup(slave), "w", encoding="utf-8")
    shown = bytearray()
    loop = asyncio.get_running_loop()
    os.set_blocking(master, False)

    def read_screen() -> None:
        with contextlib.suppress(OSError):
            shown.extend(os.read(master, 65536))

    async def until(predicate: Callable[[], bool], what: str) -> None:
        deadline = time.monotonic() + 10
        while not predicate():
            assert time.monotonic() < deadline, f"no {what} in {bytes(shown)!r}"
            await asyncio.sleep(0.02)

    def waiting_keys() -> int:
        """Keys the terminal holds for the next read (whole lines only, in cooked mode)."""
        return int(struct.unpack("i", fcntl.ioctl(slave, termios.FIONREAD, b"\0" * 4))[0])

    modes = termios.tcgetattr(slave)
    engine = Engine("127.0.0.1", port=server.port, timeout=15)
    task: asyncio.Task[int] | None = None
    loop.add_reader(master, read_screen)
    try:
        repl = Repl(
            engine,
            History(tmp_path / "history"),
            make_console(file=screen_file, force_terminal=True, width=100, color_system=None),
            input=Vt100Input(keys),
            output=Vt100_Output(
                screen_file, lambda: Size(rows=30, columns=100), term="xterm", enable_cpr=False
            ),
        )
        task = asyncio.create_task(repl.run())
        await until(lambda: b"LIVE" in shown, "banner")
        os.write(master, b"get I 1\r")
        await until(lambda: b"GET:RC8:1:I:\r" in server.received, "GET on the wire")
        echoed_from = len(shown)
        os.write(master, b"get I 2")  # typed ahead, no Enter yet
        await until(
            lambda: b"get I 2" in shown[echoed_from:] or waiting_keys() >= len("get I 2"),
            "the typed keys taken by the terminal (echoed, or held for the next prompt)",
        )
        reply.release.set()
        await until(lambda: b"I1 = 1" in shown, "the first result")
        os.write(master, b"\r")
        await until(lambda: b"I2 = 250" in shown, "the typed-ahead line run")
        os.write(master, b"quit\r")
        await asyncio.wait_for(task, 10)
        assert termios.tcgetattr(slave) == modes  # echo and line editing back as they were
    finally:
        reply.release.set()
        if task is not None and not task.done():  # a failed step: end the REPL here
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)
            engine.stop()
        loop.remove_reader(master)
        server.close()
        keys.close()
        screen_file.close()
        os.close(slave)
        os.close(master)
    lines = Screen(100).feed(shown.decode("utf-8", "replace")).lines()
    results = [line for line in lines if "I1 = 1" in line]
    assert results and all(line.startswith("I1 = 1 ") for line in results), lines
    prompt = lines[lines.index(results[0]) + 1]
    assert prompt.endswith("> get I 2"), lines  # the keys typed ahead, on the next prompt
