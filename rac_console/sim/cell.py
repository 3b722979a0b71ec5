"""A simulated cell: several simulators in one process, playing a handshake.

So that a cell can be tried and tested with no robot (``rac-console --cell demo``,
``rac-console sim --cell N``): robotA places a part every CYCLE seconds (its IO 128,
"part placed", on for HOLD seconds); robotB answers REACTION seconds after it sees the
part (its IO 64, "go", on) and lets go when robotA's output goes off. Further
simulators (robotC, ...) run as the plain simulator does (I 0 counts, IO 0-7 blink).
The handshake changes the simulators' values directly, not over RAC.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Sequence

from .controller import SimulatedController
from .server import SimulatorServer
from .thread import LoopThread

#: The simulators' names, in order (a cell's target names).
NAMES = tuple(f"robot{letter}" for letter in "ABCDEFGH")
PART_PLACED = ("IO", 128)  # robotA's output
GO = ("IO", 64)  # robotB's answer
#: What ``--cell demo`` watches from the start: the handshake, each on its robot.
DEMO_WATCH = (f"{NAMES[0]} IO 128 part placed", f"{NAMES[1]} IO 64 go")
CYCLE = 4.0
HOLD = 1.5
REACTION = 0.35


class SimulatedCell:
    """``count`` simulators on one event loop; ``start()`` returns once all listen."""

    def __init__(
        self,
        count: int = 2,
        *,
        cycle: float = CYCLE,
        hold: float = HOLD,
        reaction: float = REACTION,
        host: str = "127.0.0.1",
        ports: tuple[int, ...] = (),
        servers: Sequence[SimulatorServer] = (),
    ) -> None:
        """``servers``: made by the caller (``rac-console sim --cell N``: its faults,
        its notices), each over a :class:`SimulatedController`; else ``count`` plain
        ones on ``host`` and ``ports`` (0: any free port)."""
        count = len(servers) or count
        if not 1 <= count <= len(NAMES):
            raise ValueError(f"a simulated cell has 1 to {len(NAMES)} simulators, not {count}")
        self.cycle, self.hold, self.reaction = cycle, hold, reaction
        wanted = ports or (0,) * count
        self.servers = tuple(servers) or tuple(
            SimulatorServer(host, port, controller=SimulatedController()) for port in wanted
        )
        self._handshake: asyncio.Task[None] | None = None

    @property
    def names(self) -> tuple[str, ...]:
        return NAMES[: len(self.servers)]

    @property
    def addresses(self) -> list[tuple[str, str, int]]:
        """(name, host, port) of each simulator, in order."""
        return [(n, s.host, s.port) for n, s in zip(self.names, self.servers, strict=True)]

    async def start(self) -> SimulatedCell:
        for server in self.servers:
            await server.start()
        self.play()
        return self

    def play(self) -> None:
        """Begin the handshake (the servers listen already: ``sim --cell`` starts them
        itself, so that all of them start or none does)."""
        if len(self.servers) > 1 and self._handshake is None:
            placer, answerer = (s.controller for s in self.servers[:2])
            assert isinstance(placer, SimulatedController)
            assert isinstance(answerer, SimulatedController)
            placer.set(*PART_PLACED, False)  # no part placed yet, no answer yet
            answerer.set(*GO, False)
            self._handshake = asyncio.create_task(self._play())

    async def stop(self) -> None:
        if self._handshake is not None:
            self._handshake.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._handshake
        for server in self.servers:
            await server.stop()

    async def _play(self) -> None:
        """robotA places a part, robotB answers a moment later; again every cycle."""
        placer, answerer = (s.controller for s in self.servers[:2])
        assert isinstance(placer, SimulatedController)
        assert isinstance(answerer, SimulatedController)
        while True:
            await asyncio.sleep(self.cycle - self.hold)
            placer.set(*PART_PLACED, True)
            await asyncio.sleep(self.reaction)
            answerer.set(*GO, True)
            await asyncio.sleep(self.hold - self.reaction)
            placer.set(*PART_PLACED, False)
            await asyncio.sleep(self.reaction)
            answerer.set(*GO, False)


class SimulatedCellThread(LoopThread):
    """A simulated cell on a thread of its own (the console's ``--cell demo``)."""

    def __init__(
        self,
        count: int = 2,
        *,
        cycle: float = CYCLE,
        hold: float = HOLD,
        reaction: float = REACTION,
    ) -> None:
        super().__init__("rac-sim-cell")
        self.cell = SimulatedCell(count, cycle=cycle, hold=hold, reaction=reaction)

    def start(self) -> SimulatedCellThread:
        self.start_loop(self.cell.start)
        return self

    def stop(self) -> None:
        self.stop_loop(self.cell.stop)

    def stop_one(self, index: int) -> None:
        """One simulator goes away (a controller switched off); the others go on."""
        self.run(self.cell.servers[index].stop, 5)

    def __enter__(self) -> SimulatedCellThread:
        return self.start()

    def __exit__(self, *exc_info: object) -> None:
        self.stop()
