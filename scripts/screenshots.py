"""Regenerate screenshots/ from the real console running against the built-in simulator.

    python scripts/screenshots.py [SCENE...]

Each screenshot is taken after typing real commands and letting polling run.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import shutil
import sys
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

from rac_console.agent.client import attach
from rac_console.agent.server import Agent
from rac_console.commands.plant import parse_mqtt_address
from rac_console.commands.policy import TargetProfile, WritePolicy, Writes, parse_allow
from rac_console.commands.target import Target
from rac_console.engine import Engine, EngineLike
from rac_console.engine.cell.cell import Cell
from rac_console.engine.setup.options import EngineOptions
from rac_console.engine.setup.where import Where
from rac_console.present.history import History
from rac_console.sim.cell import SimulatedCellThread
from rac_console.sim.thread import SimulatorThread
from rac_console.tui.app import RacConsoleApp

OUT = Path(__file__).resolve().parent.parent / "screenshots"

SCENES = {
    "console-120x40": (
        (120, 40),
        [
            "watch P 0 current pose",
            "watch J 0",
            "watch I 0 cycle",
            "watch IO 0-7",
            "watch IO 128-131",
            "get P 1",
            "put IO 20 on",
            "PUT:RC8:10:11,0",
            "send hello",
        ],
        "",
    ),
    "console-80x24": ((80, 24), ["watch IO 0-3", "watch I 0 cycle", "get S 1"], "put P 10 "),
    "console-200x50": (
        (200, 50),
        [
            "watch P 0 current pose",
            "watch J 0",
            "watch T 1 tool",
            "watch F 0 motor temp",
            "watch IO 0-7",
            "watch S 2",
            "get P 1",
            "put P 10 1 2 3",
            "put I 10 123",
            "get I 10",
        ],
        "",
    ),
    "completion": ((100, 30), ["watch P 1"], "get "),
}

#: Scenes that press keys after their lines (and a pause): the I/O grid, a trend.
KEYED_SCENES = {
    "io-grid-80x24": (
        (80, 24),
        ["watch IO 0-31", "watch IO 128-159", "watch I 0 cycle", "put IO 20 on", "put IO 129 on"],
        ["f5"],
    ),
    "io-grid-120x40": (
        (120, 40),
        ["watch IO 0-15", "watch IO 128 gripper closed", "watch IO 129-143", "watch P 0 pose"],
        ["f5"],
    ),
    "trend-120x40": (
        (120, 40),
        ["watch P 0 current pose", "watch I 0 cycle", "watch F 0 motor temp", "watch J 0"],
        ["f6", "down", "t"],
    ),
    "hex-view-120x40": (
        (120, 40),
        ["watch I 0 cycle", "get I 1", "put I 10 15", "send hello", "get S 1"],
        ["f7"],
    ),
    "detail-80x24": (
        (80, 24),
        ["watch P 0 current pose", "watch J 0", "watch T 1 tool", "watch I 0 cycle"],
        ["f6", "d"],
    ),
    "help-80x24": ((80, 24), ["watch IO 0-3"], ["f1"]),
    "palette-100x30": ((100, 30), ["watch IO 0-3"], ["ctrl+p"]),
}

#: Scenes on a LIVE target profile (a simulator served on loopback, named cell3):
#: its colour frames the console; the second one is a write waiting for its "y".
PROFILE_SCENES = {
    "profile-live-120x40": ((120, 40), ["watch IO 128-135", "watch I 10 part count"], ""),
    "confirm-120x40": ((120, 40), ["watch I 10 part count", "watch IO 128-135"], "put I 10 15\n"),
}


#: A cell of two simulators playing the handshake (robotA places a part on IO 128,
#: robotB answers on IO 64): their trends overlaid (t on robotA's row, T on robotB's).
CELL_SCENES = {
    "cell": (
        (120, 40),
        [
            "watch IO 128 part placed",
            "watch I 10 parts",
            "@robotB watch IO 64 go",
            "@robotB watch I 10 parts",
            "@robotB put I 10 7",
        ],
        ["f6", "t", "down", "down", "T", "f6"],  # t leaves the table the keys
    ),
}


#: The console publishing to a mosquitto started here (Debian's package), the MQTT badge
#: on its status line, and ``publish`` saying where the values go.
PLANT_SCENES = {
    "plant-120x40": (
        (120, 40),
        ["watch P 0 current pose", "watch IO 128-131", "watch I 0 cycle", "publish"],
        "",
    ),
}


#: The console publishing to a broker that announces a 256 MB CONNACK (the tests' own,
#: tests/support/brokers.py): dropped in one line, the badge red, polling going on.
HOSTILE_SCENES = {
    "plant-hostile-120x40": (
        (120, 40),
        ["watch P 0 current pose", "watch IO 128-131", "watch I 0 cycle"],
        "",
    ),
}


#: The console through an agent (``via agent`` on its status line), its poll frames
#: hidden (F3), with another client of the agent (a REPL) writing I 10: its PUT and
#: read-back in the console's frame log, tagged with who sent them.
AGENT_SCENES = {
    "agent-120x40": ((120, 40), ["watch I 10 parts", "watch IO 128-131"], ["f3"]),
}


@contextlib.contextmanager
def agent_holding(port: int) -> Iterator[Target]:
    """An agent of this process holding the simulator at ``port``, in a folder of its own."""
    with tempfile.TemporaryDirectory() as folder:
        os.environ["RAC_CONSOLE_AGENT_DIR"] = folder
        target = Target("127.0.0.1", port)
        agent = Agent([("sim", target)], say=lambda text: None)
        agent.open()
        threading.Thread(target=agent.serve, daemon=True).start()
        try:
            yield target
        finally:
            agent.stop()
            del os.environ["RAC_CONSOLE_AGENT_DIR"]


@contextlib.contextmanager
def mosquitto() -> Iterator[int | None]:
    """The benchmark's broker (benchmarks/plant_publish.py) on a free port; None when
    mosquitto is not installed."""
    if shutil.which("mosquitto") is None and shutil.which("mosquitto", path="/usr/sbin") is None:
        print("plant-120x40: needs mosquitto (apt install mosquitto)", file=sys.stderr)
        yield None
        return
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
    from plant_publish import Mosquitto

    with tempfile.TemporaryDirectory() as folder:
        broker = Mosquitto(Path(folder), None)
        try:
            yield broker.port
        finally:
            broker.stop()


def cell_of(sims: SimulatedCellThread) -> Cell:
    """A cell on the simulators: a profile each (a colour, a label)."""
    targets = []
    for (name, host, port), colour in zip(sims.cell.addresses, ("green", "magenta"), strict=False):
        profile = TargetProfile(name, host, port, f"Cell {name[-1]}", colour, WritePolicy())
        targets.append((name, Target(host, port, profile=profile)))
    return Cell(targets, options=EngineOptions(interval=0.2, cycles=True))


def profile_engine(port: int) -> Engine:
    """An engine on profile cell3: a LIVE target that asks before every write."""
    policy = WritePolicy(
        Writes.CONFIRM, (parse_allow("I 0-99"), parse_allow("IO 128-143")), "profile cell3"
    )
    profile = TargetProfile("cell3", "127.0.0.1", port, "Cell 3 — welding", "red", policy)
    return Engine("127.0.0.1", port, interval=0.2, cycles=True, policy=policy, profile=profile)


async def take(
    name: str,
    size: tuple[int, int],
    lines: list[str],
    typed: str,
    keys: list[str] | None = None,
    engine: EngineLike | Cell | None = None,
) -> None:
    with tempfile.TemporaryDirectory() as home:
        engine = engine or Engine(None, interval=0.2, cycles=True)
        app = RacConsoleApp(engine, History(Path(home) / "history"))
        async with app.run_test(size=size) as pilot:
            for line in lines:
                app.main_screen.panes.command_line.insert_text_at_cursor(line)
                await pilot.press("enter")
                await pilot.pause(0.15)
            await pilot.pause(1.2)
            if keys:
                await pilot.press(*keys)
                await pilot.pause(4.0)  # a trend of a few seconds
            if typed:
                line, enter = typed.removesuffix("\n"), typed.endswith("\n")
                await pilot.press(*line, *(["enter"] if enter else []))
                if name == "completion":
                    await pilot.press("tab")
                await pilot.pause(0.6)
            app.main_screen.panes.command_line.cursor_blink = False
            app.save_screenshot(f"{name}.svg", str(OUT))
    print(f"wrote screenshots/{name}.svg", file=sys.stderr)


async def main(only: list[str]) -> None:
    """Every scene, or the ones named on the command line."""
    OUT.mkdir(exist_ok=True)

    def wanted(name: str) -> bool:
        return not only or name in only

    for name, (size, lines, typed) in SCENES.items():
        if wanted(name):
            await take(name, size, lines, typed)
    for name, (size, lines, keys) in KEYED_SCENES.items():
        if wanted(name):
            await take(name, size, lines, "", keys)
    for name, (size, lines, typed) in PROFILE_SCENES.items():
        if not wanted(name):
            continue
        with SimulatorThread() as sim:
            await take(name, size, lines, typed, engine=profile_engine(sim.port))
    for name, (size, lines, typed) in PLANT_SCENES.items():
        if not wanted(name):
            continue
        with mosquitto() as port:
            if port is not None:
                address = parse_mqtt_address(f"mqtt://127.0.0.1:{port}/line2")
                engine = Engine(None, interval=0.2, cycles=True, publish=address)
                await take(name, size, lines, typed, engine=engine)
    for name, (size, lines, typed) in HOSTILE_SCENES.items():
        if not wanted(name):
            continue
        sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
        from tests.support.brokers import hostile_broker

        hostile = hostile_broker("a 256 MB CONNACK")
        try:
            address = parse_mqtt_address(f"mqtt://127.0.0.1:{hostile.port}/line2")
            engine = Engine(None, interval=0.2, cycles=True, publish=address)
            await take(name, size, lines, typed, engine=engine)
        finally:
            hostile.close()
    for name, (size, lines, keys) in AGENT_SCENES.items():
        if not wanted(name):
            continue
        with SimulatorThread() as sim, agent_holding(sim.port) as target:
            options = EngineOptions(interval=0.2, cycles=True)
            console = attach(target, options, client="console", where=Where.CONSOLE)
            other = attach(target, EngineOptions(), client="REPL", where=Where.REPL)
            assert console is not None and other is not None
            other.start()
            writes = threading.Timer(3.0, other.submit, args=("put I 10 7",))
            writes.start()
            try:
                await take(name, size, lines, "", keys, engine=console)
            finally:
                writes.cancel()
                other.stop()
    for name, (size, lines, keys) in CELL_SCENES.items():
        if wanted(name):
            with SimulatedCellThread(2) as sims:
                await take(name, size, lines, "", keys, engine=cell_of(sims))


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1:]))
