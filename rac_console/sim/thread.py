"""The simulator on a thread of its own, for callers without an event loop.

The console's engine and the one-shot CLI talk to the built-in simulator over a real
socket (loopback TCP, or a socket pair that no other process can reach); the
simulator's asyncio server runs here, on its own loop, so the caller's blocking session
never shares a thread with it.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar

from .server import Connection, SimulatorServer

T = TypeVar("T")


class LoopThread:
    """An event loop on a daemon thread: servers started and stopped on it."""

    def __init__(self, name: str) -> None:
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name=name, daemon=True)

    def run(self, job: Callable[[], Awaitable[T]], timeout: float) -> T:
        """``job()`` on the loop, waited for (``timeout`` seconds at most)."""

        async def call() -> T:
            return await job()

        return asyncio.run_coroutine_threadsafe(call(), self._loop).result(timeout)

    def start_loop(self, started: Callable[[], Awaitable[Any]]) -> None:
        self._thread.start()
        self.run(started, 10)

    def stop_loop(self, stopped: Callable[[], Awaitable[Any]]) -> None:
        if not self._thread.is_alive():
            return
        try:
            self.run(stopped, 5)
        finally:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(5)
            if not self._thread.is_alive():
                self._loop.close()


class SimulatorThread(LoopThread):
    """``start()`` returns once the simulator listens; ``host``/``port`` say where.
    ``listen=False``: it listens on no port, and :meth:`connect` is the only way in."""

    def __init__(self, listen: bool = True) -> None:
        super().__init__("rac-sim")
        self.server = SimulatorServer(listen=listen)

    def connect(self) -> Connection:
        """A connection to the simulator that only this process holds (see
        :meth:`.server.SimulatorServer.connect`)."""
        return self.server.connect()

    @property
    def host(self) -> str:
        return self.server.host

    @property
    def port(self) -> int:
        return self.server.port

    def start(self) -> SimulatorThread:
        self.start_loop(self.server.start)
        return self

    def stop(self) -> None:
        self.stop_loop(self.server.stop)

    def __enter__(self) -> SimulatorThread:
        return self.start()

    def __exit__(self, *exc_info: object) -> None:
        self.stop()
