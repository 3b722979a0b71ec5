"""The blocking session, driven from a worker thread of its own, for asyncio tests.

Many tests run their hostile servers (or the simulator) on the test's event loop; a
blocking request made on that loop's thread would starve them. :class:`AsyncSession`
runs every call of one :class:`~rac_console.session.Session` on one worker thread (the
session's owner, as the engine's thread is in the console) and awaits it.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, TypeVar

from rac_console.protocol import Variant, VarKind
from rac_console.protocol.request import raw_request
from rac_console.session import Frame, Reply, Session

T = TypeVar("T")


class AsyncSession:
    def __init__(self, host: str, port: int, **options: Any) -> None:
        self.session = Session(host, port, **options)
        self._owner = ThreadPoolExecutor(max_workers=1, thread_name_prefix="test-session")

    async def _call(self, function: Callable[..., T], *args: Any, **kwargs: Any) -> T:
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self._owner, lambda: function(*args, **kwargs))

    async def get(self, kind: VarKind, index: int) -> Reply:
        return await self._call(self.session.get, kind, index)

    async def put(self, kind: VarKind, index: int, value: Variant) -> Reply:
        return await self._call(self.session.put, kind, index, value)

    async def send_raw(self, text: str) -> Reply:
        return await self._call(self.session.send_raw, text)

    async def request(self, text: str) -> Reply:
        return await self._call(self.session.exchange, raw_request(text))

    async def connect(self) -> None:
        await self._call(self.session.connect)

    async def close(self) -> None:
        await self._call(self.session.close)
        self._owner.shutdown(wait=False)

    def has_unread(self, timeout: float = 0.0) -> bool:
        return self.session.has_unread(timeout)

    def add_frame_observer(self, observer: Callable[[Frame], None]) -> None:
        self.session.add_frame_observer(observer)

    @property
    def state(self) -> str:
        return self.session.state

    @property
    def last_rtt(self) -> float | None:
        return self.session.last_rtt

    async def __aenter__(self) -> AsyncSession:
        return self

    async def __aexit__(self, *exc_info: object) -> None:
        await self.close()
