"""The library awaited: ``async with rac.aio.connect("robot3") as rc: await rc.get("I", 1)``.

The same connection as :func:`rac_console.connect`, its calls run on a thread of its own
(one per connection), one at a time in the order they start: ``asyncio.gather(rc.get("I",
1), rc.get("I", 2))`` sends the two GETs one after the other, each call getting its own
answer, and the event loop never waits on the network.

A call cancelled before its turn is never sent. One cancelled while its request is on
the wire runs to its end on that thread, and its result is lost to the caller: for a PUT
that means the write may have happened (check it with a get).
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable, Generator
from concurrent.futures import ThreadPoolExecutor
from functools import partial, wraps
from typing import Any, Generic, Literal, ParamSpec, Self, TypeVar, overload

from .commands.language import VarRef
from .library.cell import Cell
from .library.cell import cell as open_cell
from .library.connection import EVERY, Connection, watch_list, watch_period
from .library.connection import connect as open_connection
from .library.errors import Refused
from .library.results import Reading, Sent, Value, Written

__all__ = ["AsyncCell", "AsyncConnection", "cell", "connect"]

T = TypeVar("T")
P = ParamSpec("P")
Opened = TypeVar("Opened", Connection, Cell)


class _Thread:
    """One thread for one connection (or cell): what it is asked runs there, in order."""

    def __init__(self) -> None:
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rac-aio")
        self.closed = False

    async def call(self, work: Callable[..., T], *args: Any) -> T:
        if self.closed:
            raise Refused("the connection is closed: nothing was sent (connect again)")
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self._executor, partial(work, *args))

    async def open(self, opening: Callable[[], Opened]) -> Opened:
        """``opening()`` on the thread; closed there too if the caller gave up waiting."""
        future = asyncio.get_running_loop().run_in_executor(self._executor, opening)
        try:
            return await future
        except asyncio.CancelledError:
            future.add_done_callback(_close_opened)
            self.closed = True
            self._executor.shutdown(wait=False)
            raise

    async def close(self, closing: Callable[[], None] | None) -> None:
        """``closing()`` after every call asked before it; the thread then ends."""
        if self.closed:
            return
        try:
            if closing is not None:
                await self.call(closing)
        finally:
            self.closed = True
            self._executor.shutdown(wait=False)


def _close_opened(future: asyncio.Future[Any]) -> None:
    """A connection opened for a caller that stopped waiting: closed, on the thread."""
    if not future.cancelled() and future.exception() is None:
        future.result().close()


class _Awaited(Generic[Opened]):
    """What a connection and a cell share awaited: opened by ``async with`` or ``await``
    on a thread of their own, and closed there once every call asked before has run."""

    #: How a call made before the opening names the way to open it.
    _OPEN_FIRST = "not connected yet: async with rac.aio.connect(...) as rc"

    def __init__(self, opening: Callable[[], Opened]) -> None:
        self._opening: Callable[[], Opened] = opening
        self._thread = _Thread()
        self._value: Opened | None = None

    async def open(self) -> Self:
        """Connect (once); ConnectionFailed or Refused as the library's own."""
        if self._value is None:
            self._value = await self._thread.open(self._opening)
        return self

    def __await__(self) -> Generator[Any, None, Self]:
        return self.open().__await__()

    async def __aenter__(self) -> Self:
        return await self.open()

    async def __aexit__(self, *exc_info: object) -> None:
        await self.close()

    async def close(self) -> None:
        """Close once every call asked before has run."""
        value = self._value
        await self._thread.close(value.close if value is not None else None)

    @property
    def _opened(self) -> Opened:
        if self._value is None:
            raise Refused(self._OPEN_FIRST)
        return self._value


class AsyncConnection(_Awaited[Connection]):
    """One controller, awaited: ``await rc.get(...)``, ``put``, ``send``, ``async for
    reading in rc.watch(...)``. Opened by ``async with`` or ``await``."""

    @property
    def connection(self) -> Connection:
        """The connection below (its host, port, profile, writes)."""
        return self._opened

    @overload
    async def get(self, kind: Literal["I", "i"], index: int) -> int: ...
    @overload
    async def get(self, kind: Literal["F", "f", "D", "d"], index: int) -> float: ...
    @overload
    async def get(self, kind: Literal["S", "s"], index: int) -> str: ...
    @overload
    async def get(self, kind: Literal["IO", "io", "Io", "iO"], index: int) -> bool: ...
    @overload
    async def get(
        self, kind: Literal["V", "v", "P", "p", "J", "j", "T", "t"], index: int
    ) -> tuple[float, ...]: ...
    @overload
    async def get(self, kind: str, index: int) -> Value: ...
    async def get(self, kind: str, index: int) -> Value:
        """:meth:`rac_console.Connection.get`, awaited."""
        return await self._thread.call(self.connection.get, kind, index)

    async def put(self, kind: str, index: int, value: Value, *, verify: bool = True) -> Written:
        """:meth:`rac_console.Connection.put`, awaited (see the module on cancelling)."""
        return await self._thread.call(
            partial(self.connection.put, verify=verify), kind, index, value
        )

    async def send(self, line: str) -> Sent:
        """:meth:`rac_console.Connection.send`, awaited."""
        return await self._thread.call(self.connection.send, line)

    def watch(self, *variables: str, every: float = EVERY) -> AsyncIterator[Reading]:
        """:meth:`rac_console.Connection.watch`, as an async iterator: the waits between
        cycles are the event loop's, and other calls run between cycles."""
        return self._watching(watch_list(variables), watch_period(every))

    async def _watching(self, watched: tuple[VarRef, ...], period: float) -> AsyncIterator[Reading]:
        loop = asyncio.get_running_loop()
        due = loop.time()
        while True:
            for reading in await self._thread.call(self.connection._cycle, watched):
                yield reading
            due += period
            wait = due - loop.time()
            if wait > 0:
                await asyncio.sleep(wait)
            else:
                due = loop.time()


def _awaited(
    opening: Callable[P, Opened], face: Callable[[Callable[[], Opened]], T], doc: str
) -> Callable[P, T]:
    """``opening``'s parameters (one signature for both faces), its result opened awaited
    (``face``)."""

    @wraps(opening)
    def awaited(*args: P.args, **kwargs: P.kwargs) -> T:
        return face(partial(opening, *args, **kwargs))

    awaited.__doc__ = doc
    return awaited


connect = _awaited(
    open_connection,
    AsyncConnection,
    """:func:`rac_console.connect`, awaited: ``async with rac.aio.connect("sim") as rc``
    (or ``rc = await rac.aio.connect("sim")``, then ``await rc.close()``); the same
    parameters. ``confirm`` is called on the connection's thread.""",
)


class AsyncCell(_Awaited[Cell]):
    """:class:`rac_console.Cell`, awaited: ``await cell.run("@robotA put I 10 5")``. Its
    lines run one at a time on one thread of the cell's, in the order they start."""

    _OPEN_FIRST = "not connected yet: async with rac.aio.cell(...) as cell"

    @property
    def names(self) -> tuple[str, ...]:
        return self._opened.names

    async def run(self, line: str) -> Value | Written | Sent | None:
        """:meth:`rac_console.Cell.run`, awaited: one line at a time, in order."""
        return await self._thread.call(self._opened.run, line)


cell = _awaited(
    open_cell,
    AsyncCell,
    """:func:`rac_console.cell`, awaited: ``async with rac.aio.cell("demo") as cell``; the
    same parameters.""",
)
