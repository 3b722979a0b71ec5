"""The simulator's asyncio TCP server: many sessions over one SimulatedController."""

from __future__ import annotations

import asyncio
import ipaddress

from ..protocol import FrameTooLong, LineDecoder
from ..protocol.hresult import E_INVALIDRCVPACKET
from .controller import MAX_REQUEST, SimulatedController, _reply

LOOPBACK = "127.0.0.1"


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class _SimSession(asyncio.Protocol):
    """One client connection. Reading pauses while the client is not reading,
    so a client that never reads cannot make the server buffer without bound."""

    def __init__(self, server: SimulatorServer) -> None:
        self._server = server
        self._decoder = LineDecoder(MAX_REQUEST - 1)
        self._transport: asyncio.Transport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self._transport = transport  # type: ignore[assignment]
        self._server.sessions.add(self)

    def connection_lost(self, exc: Exception | None) -> None:
        self._server.sessions.discard(self)
        self._transport = None

    def data_received(self, data: bytes) -> None:
        transport = self._transport
        if transport is None or transport.is_closing():
            return
        too_long = False
        try:
            lines = self._decoder.feed(data)
        except FrameTooLong as exc:
            lines, too_long = exc.lines, True
        controller = self._server.controller
        for line in lines:
            reply, close = controller.handle(line)
            transport.write(reply)
            if close:
                transport.close()
                return
        if too_long:
            transport.write(_reply(E_INVALIDRCVPACKET))
            transport.close()

    def pause_writing(self) -> None:
        if self._transport is not None:
            self._transport.pause_reading()

    def resume_writing(self) -> None:
        if self._transport is not None and not self._transport.is_closing():
            self._transport.resume_reading()

    def abort(self) -> None:
        if self._transport is not None:
            self._transport.abort()


class SimulatorServer:
    """``async with SimulatorServer() as sim:`` serves on ``sim.host:sim.port``."""

    def __init__(
        self,
        host: str = LOOPBACK,
        port: int = 0,
        controller: SimulatedController | None = None,
    ) -> None:
        self.host = host
        self.port = port
        self.controller = controller or SimulatedController()
        self.sessions: set[_SimSession] = set()
        self._server: asyncio.Server | None = None

    async def start(self) -> SimulatorServer:
        loop = asyncio.get_running_loop()
        self._server = await loop.create_server(
            lambda: _SimSession(self), self.host, self.port, reuse_address=True
        )
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
            for session in list(self.sessions):
                session.abort()
            await self._server.wait_closed()
            self._server = None

    async def serve_forever(self) -> None:
        assert self._server is not None
        await self._server.serve_forever()

    async def __aenter__(self) -> SimulatorServer:
        return await self.start()

    async def __aexit__(self, *exc_info: object) -> None:
        await self.stop()
