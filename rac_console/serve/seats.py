"""The session slots, over the sockets: :class:`~.guard.Slots` decides who holds one;
this module closes the socket of a session whose slot a newer page took (with
:data:`~.page.TAKEN_CODE`, which its page says), and holds a new session until the
console it displaced has ended, so that consoles never outnumber the slots.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable

from aiohttp import web

from .guard import Slots
from .page import TAKEN_CODE, TAKEN_REASON


class Seat:
    """One session's hold on a slot."""

    def __init__(self, websocket: web.WebSocketResponse) -> None:
        self.websocket = websocket
        self.started = False  # its console was started (it counts until it ended)
        self.taken = False
        self._closing: asyncio.Task[bool] | None = None

    def take_away(self) -> None:
        """A newer page took the slot: the socket is closed, saying so; the session's
        console is then stopped as for any closed socket."""
        self.taken = True
        if not self.websocket.closed and self._closing is None:
            self._closing = asyncio.get_running_loop().create_task(
                self.websocket.close(code=TAKEN_CODE, message=TAKEN_REASON.encode())
            )


class Seats:
    """Who sits, and the wait for a console to end before the next starts."""

    def __init__(self, slots: Slots, said_taken: Callable[[], None] = lambda: None) -> None:
        self.slots = slots
        self.said_taken = said_taken
        self._changed = asyncio.Condition()

    async def sit(self, seat: Seat) -> bool:
        """``seat`` takes a slot (the oldest holder beyond the limit loses its own);
        True once its console may start, False when a newer page took the slot first."""
        async with self._changed:
            for old in self.slots.claim(seat):
                assert isinstance(old, Seat)
                old.take_away()
                self.said_taken()
            self._changed.notify_all()  # a displaced seat still waiting gives up
            await self._changed.wait_for(
                lambda: not self.slots.holds(seat) or self.slots.may_start(seat)
            )
            if not self.slots.may_start(seat):
                return False
            self.slots.started()
            seat.started = True
            return True

    async def leave(self, seat: Seat) -> None:
        """``seat``'s session is over (its console, if it started one, has ended)."""
        async with self._changed:
            self.slots.leave(seat, seat.started)
            self._changed.notify_all()
        if seat.taken and not seat.websocket.closed:
            with contextlib.suppress(Exception):
                await seat.websocket.close(code=TAKEN_CODE, message=TAKEN_REASON.encode())
