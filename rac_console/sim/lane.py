"""The simulator's plain path on Linux: sessions served straight off an epoll set.

asyncio serves each readable connection as a callback of its own, through a transport
and a protocol: for clients that each keep one request in flight, that dispatch was
most of what a request cost (0.6x the requests a C epoll server answers over 50
sessions). Here one reader callback on the loop takes every ready session in one pass
and reads, answers and sends with the socket's own calls, as the C server does.

Only the plain path is served here: each read's requests answered at once and their
replies sent whole. A session that needs more leaves for an asyncio transport
(``SimSession.hand_over``) with what it still owes, and stays there: when its client
does not take a reply whole (the transport then paces it and stops reading it), and
when a read arrives while faults or a transcript are on. Linux only (``select.epoll``,
on a loop that can watch a descriptor); elsewhere every session has a transport.
"""

from __future__ import annotations

import asyncio
import contextlib
import select
import socket
import time
from typing import Protocol

from ..protocol.hresult import E_INVALIDRCVPACKET
from .controller import code_reply
from .notices import Notices
from .session import READ_SIZE, WRITE_BATCH, Host, Owed, SimSession


class LaneHost(Host, Protocol):
    """What the lane needs of its server (:class:`~.server.SimulatorServer`, which
    imports this module) beyond what a session does."""

    notices: Notices

    @property
    def plain(self) -> bool: ...
    def adopt(self, session: SimSession, conn: socket.socket) -> None: ...


class FastLane:
    """Sessions on an epoll set of their own, whose descriptor the loop watches."""

    def __init__(
        self, server: LaneHost, loop: asyncio.AbstractEventLoop, epoll: select.epoll
    ) -> None:
        self._server = server
        self._loop = loop
        self._epoll = epoll
        self._sessions: dict[int, tuple[SimSession, socket.socket]] = {}  # by descriptor

    @classmethod
    def open(cls, server: LaneHost, loop: asyncio.AbstractEventLoop) -> FastLane | None:
        """A lane on ``loop``; None without epoll, or on a loop that cannot watch a
        descriptor (Windows' proactor)."""
        if not hasattr(select, "epoll"):
            return None
        epoll = select.epoll()
        lane = cls(server, loop, epoll)
        try:
            loop.add_reader(epoll.fileno(), lane._ready)
        except NotImplementedError:
            epoll.close()
            return None
        return lane

    def close(self) -> None:
        """Stop watching, dropping the sessions still here."""
        for session, _ in list(self._sessions.values()):
            self.drop(session)
        with contextlib.suppress(RuntimeError):  # the loop is closed already: nothing to undo
            self._loop.remove_reader(self._epoll.fileno())
        self._epoll.close()

    def admit(self, sock: socket.socket) -> None:
        """Serve a new client here (the server checked max_sessions); OSError, with
        nothing changed, if it cannot be watched."""
        sock.setblocking(False)
        with contextlib.suppress(OSError):  # as asyncio's transports do: replies go out at once
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        fd = sock.fileno()
        self._epoll.register(fd, select.EPOLLIN)
        session = SimSession(self._server, sock)
        session.lane = self
        self._sessions[fd] = (session, sock)
        self._server.sessions.add(session)

    def drop(self, session: SimSession) -> None:
        """Close a session served here: its client left, or the server closes it."""
        sock = session.sock
        if sock is None or session.lane is not self:
            return
        self._forget(sock)
        sock.close()
        session.connection_lost(None)

    def _forget(self, sock: socket.socket) -> None:
        fd = sock.fileno()
        self._epoll.unregister(fd)
        del self._sessions[fd]

    def _hand_over(
        self,
        session: SimSession,
        sock: socket.socket,
        owed: Owed,
        lines: list[bytes] | None = None,
        too_long: bool = False,
    ) -> None:
        """To an asyncio transport, with what the session still owes its client."""
        self._forget(sock)
        session.hand_over(owed, lines or [], too_long)
        self._server.adopt(session, sock)

    # ------------------------------------------------------------- serving

    def _ready(self) -> None:
        """One read from each ready session, answered. A read that is one kept request
        (what a polling client sends) is answered by one dict look-up."""
        server = self._server
        sessions = self._sessions
        frames = server.fast_frames
        controller = server.controller
        now = time.monotonic()
        kept = 0  # requests answered from the kept replies, counted once at the end
        # With one session the set is ready only when it is: the poll would say nothing new.
        ready = [(fd, 0) for fd in sessions] if len(sessions) == 1 else self._epoll.poll(0)
        for fd, _ in ready:
            entry = sessions.get(fd)
            if entry is None:  # dropped earlier in this pass
                continue
            session, sock = entry
            try:
                try:
                    data = sock.recv(READ_SIZE)
                except (BlockingIOError, InterruptedError):
                    continue
                except OSError:  # reset: as a close
                    data = b""
                if not data:  # the client closed: everything it sent is answered
                    self.drop(session)
                    continue
                session.last_active = now
                reply = frames.get(data)
                if reply is None or session.partial:
                    self._answer(session, sock, data)
                    frames = server.fast_frames  # a SIM: line may have turned faults on
                    continue
                kept += 1
                try:  # _send, written out: this is every request of a polling client
                    sent = sock.send(reply)
                except (BlockingIOError, InterruptedError):
                    sent = 0
                except OSError:  # the client is gone
                    self.drop(session)
                    continue
                if sent != len(reply):
                    self._hand_over(session, sock, Owed(unsent=reply[sent:]))
            except Exception as exc:  # a bug costs that session, never the others
                server.notices.note("internal", f"internal error: {exc!r}")
                self.drop(session)
        controller.requests += kept

    def _answer(self, session: SimSession, sock: socket.socket, data: bytes) -> None:
        """A read that is not one kept request: split, answered line by line (as
        ``SimSession._take`` does on its fast path), sent in pieces of WRITE_BATCH."""
        server = self._server
        if not server.plain:  # faults or a transcript: asyncio's path from here on
            self._hand_over(session, sock, Owed(read=data))
            return
        lines, too_long = session.decode(data)
        n, count, close = 0, len(lines), False
        while n < count and not close:
            replies: list[bytes] = []
            size = 0
            while n < count and size < WRITE_BATCH and not close:
                reply, close = server.answer(lines[n])
                replies.append(reply)
                size += len(reply)
                n += 1
            if not self._send(session, sock, b"".join(replies), lines[n:], too_long, close):
                return
        if too_long and not close:
            if not self._send(session, sock, code_reply(E_INVALIDRCVPACKET), close=True):
                return
            close = True
        if close:
            self.drop(session)

    def _send(
        self,
        session: SimSession,
        sock: socket.socket,
        data: bytes,
        lines: list[bytes] | None = None,
        too_long: bool = False,
        close: bool = False,
    ) -> bool:
        """Send ``data``; True if it all went. If not, the session leaves the lane owing
        the rest, then ``lines`` (or the close)."""
        try:
            sent = sock.send(data)
        except (BlockingIOError, InterruptedError):
            sent = 0
        except OSError:  # the client is gone
            self.drop(session)
            return False
        if sent == len(data):
            return True
        self._hand_over(session, sock, Owed(unsent=data[sent:], close=close), lines, too_long)
        return False
