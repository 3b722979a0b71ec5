"""File writes off the screen's loop: history appends (under their file lock) and
settings saves (with ``fsync``) can wait on a disk or on another console's lock, and
the screen must not wait with them.

One thread runs them, one at a time, in the order they were asked for (a save never
overtakes the one before it); :meth:`FileWrites.close` waits for the last one, so what
the console saves as it ends is on disk when it has ended.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

T = TypeVar("T")


class FileWrites:
    """A queue of file writes run in order by one thread."""

    def __init__(self) -> None:
        self._thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rac-console-files")
        self._closed = False

    def run(self, write: Callable[[], T]) -> asyncio.Future[T]:
        """Queue ``write``; its outcome, awaitable (or with callbacks) on the loop."""
        return asyncio.wrap_future(self._thread.submit(write))

    async def close(self) -> None:
        """Wait for every write queued, then end the thread."""
        if not self._closed:
            self._closed = True
            await asyncio.to_thread(self._thread.shutdown, wait=True)
