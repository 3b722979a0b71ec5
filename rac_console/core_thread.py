"""Run a ConsoleCore on its own event loop in a background thread.

The Textual app paints on its loop; the session and the poller run on this one,
so a repaint never holds up the next poll (polling in the UI's loop kept only
about half of the bare client's rate). The app talks to the core only through
``submit`` and ``call``; the core talks back through thread-safe queues read by
the app's timers.
"""

from __future__ import annotations

import asyncio
import sys
import threading
from collections.abc import Callable, Coroutine
from typing import Any, TypeVar

from .core import ConsoleCore

T = TypeVar("T")

#: Let the session thread take the GIL back quickly when a reply arrives.
SWITCH_INTERVAL = 0.0001


class CoreThread:
    def __init__(self, core: ConsoleCore) -> None:
        self.core = core
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._run, name="rac-session", daemon=True)

    def _run(self) -> None:
        asyncio.set_event_loop(self.loop)
        self.loop.run_forever()
        self.loop.close()

    async def start(self) -> None:
        sys.setswitchinterval(SWITCH_INTERVAL)
        self._thread.start()
        await self.submit(self.core.start())

    def submit(self, coroutine: Coroutine[Any, Any, T]) -> asyncio.Future[T]:
        """Run a coroutine on the session loop; await the result from the caller's loop."""
        return asyncio.wrap_future(asyncio.run_coroutine_threadsafe(coroutine, self.loop))

    def call(self, function: Callable[..., object], *args: object) -> None:
        self.loop.call_soon_threadsafe(function, *args)

    async def stop(self) -> None:
        if not self._thread.is_alive():
            return
        try:
            await asyncio.wait_for(self.submit(self.core.stop()), 3)
        finally:
            self.loop.call_soon_threadsafe(self.loop.stop)
            await asyncio.to_thread(self._thread.join, 3)
