"""The simulator on a thread of its own, for callers without an event loop.

The console's engine and the one-shot CLI talk to the built-in simulator over a real
loopback socket; the simulator's asyncio server runs here, on its own loop, so the
caller's blocking session never shares a thread with it.
"""

from __future__ import annotations

import asyncio
import threading

from .server import SimulatorServer


class SimulatorThread:
    """``start()`` returns once the simulator listens; ``host``/``port`` say where."""

    def __init__(self) -> None:
        self.server = SimulatorServer()
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="rac-sim", daemon=True)

    @property
    def host(self) -> str:
        return self.server.host

    @property
    def port(self) -> int:
        return self.server.port

    def start(self) -> SimulatorThread:
        self._thread.start()
        asyncio.run_coroutine_threadsafe(self.server.start(), self._loop).result(10)
        return self

    def stop(self) -> None:
        if not self._thread.is_alive():
            return
        try:
            asyncio.run_coroutine_threadsafe(self.server.stop(), self._loop).result(5)
        finally:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(5)
            if not self._thread.is_alive():
                self._loop.close()

    def __enter__(self) -> SimulatorThread:
        return self.start()

    def __exit__(self, *exc_info: object) -> None:
        self.stop()
