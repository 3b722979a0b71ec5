"""The servers the tests write: every one binds 127.0.0.1 port 0 and stops with the test.

- :class:`RecordingServer`: a scripted controller in threads. It answers each
  CR-terminated line with ``reply(line)`` and records what came; its parameters give
  the controllers the tests need: one that keeps one session (``sessions``), one that
  answers so many lines a connection and hangs up (``answers``; 0: at once). A reply
  may close the connection (:data:`CLOSE`) or reset it (:data:`RESET`) instead.
- the replies: :func:`fixed_reply`, :class:`Answering` (changed while the server runs),
  :func:`sample_reply` (the vendor's samples), :func:`reset_first`, :class:`Memory` (a
  controller that keeps what is written, or swallows or ignores PUTs);
- :class:`Valve`: a path to the simulator whose answers the test lets through, counting
  the requests that reached it;
- :class:`FaultServer`: an asyncio server running a test's handler per connection, for
  the tests that drive the session from the event loop.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import struct
import threading
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Literal, Protocol

from tests.support.samples import GET_SAMPLES
from tests.support.sessions import AsyncSession

HOST = "127.0.0.1"


class _Close:
    """A reply that closes the connection instead of answering."""


class _Reset:
    """A reply that resets the connection (SO_LINGER 0), unanswered."""


CLOSE = _Close()
RESET = _Reset()

Answer = bytes | _Close | _Reset | None
Reply = Callable[[bytes], Answer]
#: ``many``: every connection served; ``one``: a connection made while one is open is
#: reset at once (turned away); ``newest``: the open one is reset and the newcomer served.
Sessions = Literal["many", "one", "newest"]


def unused_port() -> int:
    """A port nothing listens on (now): bound, then let go."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind((HOST, 0))
        port: int = sock.getsockname()[1]
        return port


# ------------------------------------------------------------------ replies


def fixed_reply(data: Answer) -> Reply:
    """The same answer to every line."""
    return lambda line: data


def sample_reply(line: bytes) -> bytes | None:
    """The vendor's sample answers: every GET of index 10 its sample, every PUT S_OK."""
    if line.startswith(b"PUT:"):
        return b"0\r"
    if line in GET_SAMPLES:
        return GET_SAMPLES[line] + b"\r"
    return b"0,3,123\r"


class Answering:
    """A reply that can be changed while the server runs (``None``: stay silent; a
    callable: asked for each line)."""

    def __init__(self, answer: Answer | Reply = None) -> None:
        self.answer = answer

    def __call__(self, line: bytes) -> Answer:
        if callable(self.answer):
            return self.answer(line)
        return self.answer


def reset_first(*prefixes: bytes, then: Reply) -> Reply:
    """Answers as ``then`` does, except that a line starting with one of ``prefixes``
    resets its connection, unanswered, the first time it comes."""
    pending = list(prefixes)
    lock = threading.Lock()

    def reply(line: bytes) -> Answer:
        with lock:
            hit = next((p for p in pending if line.startswith(p)), None)
            if hit is not None:
                pending.remove(hit)
                return RESET
        return then(line)

    return reply


class Memory:
    """A controller's variables as a reply, judged from its side: a PUT of
    ``PUT:RC8:<index>:<type>:<variant>`` keeps the variant and answers S_OK; a GET answers
    the variant kept (for an I never written: the index itself, ``3,<index>``, so an
    answer names its request). ``puts``: what a PUT does instead: ``"swallow"`` (taken,
    never answered) or ``"ignore"`` (S_OK, and the old value kept); ``hold``: a GET of
    this line waits until the event is set before it is answered."""

    def __init__(
        self,
        puts: Literal["keep", "swallow", "ignore"] = "keep",
        hold: tuple[bytes, threading.Event] | None = None,
    ) -> None:
        self.puts = puts
        self.hold = hold
        self.held: dict[tuple[bytes, bytes], bytes] = {}
        self._lock = threading.Lock()

    def __call__(self, line: bytes) -> Answer:
        word, _, rest = line.partition(b":")
        parts = rest.split(b":", 3)  # RC8, index, type, value
        if len(parts) < 3 or parts[0] != b"RC8":
            return b"-2147024809\r"  # E_INVALIDARG
        key = (parts[1], parts[2])
        if word == b"PUT" and len(parts) == 4:
            if self.puts == "swallow":
                return None
            if self.puts == "keep":
                with self._lock:
                    self.held[key] = parts[3]
            return b"0\r"
        if self.hold is not None and line == self.hold[0]:
            self.hold[1].wait(30)
        with self._lock:
            value = self.held.get(key, b"3," + parts[1] if parts[2] == b"I" else None)
        return b"0," + value + b"\r" if value is not None else b"-2147024809\r"


def _reset(conn: socket.socket) -> None:
    """Close with a reset (SO_LINGER 0), as a controller turning a session away."""
    with contextlib.suppress(OSError):
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    with contextlib.suppress(OSError):
        conn.close()


# ---------------------------------------------------------- the recording server


class RecordingServer:
    """A TCP server on 127.0.0.1:0 in background threads.

    It records every byte received, every line (also with the number of the connection
    it came on, 1 for the first accepted) and the order connections were accepted in,
    and answers each CR-terminated line with ``reply(line)`` (None: no answer).

    ``sessions`` (see :data:`Sessions`) says what it does with a second connection
    while one is open; ``answers``, when given, is how many lines it answers on a
    connection before closing it (0: it closes each connection as soon as it accepts
    it, before reading anything).
    """

    def __init__(
        self, reply: Reply, *, sessions: Sessions = "many", answers: int | None = None
    ) -> None:
        self.reply = reply
        self.sessions = sessions
        self.answers = answers
        self.received = bytearray()
        self.lines: list[bytes] = []
        self.numbered: list[tuple[int, bytes]] = []  # (connection, line)
        self.peers: list[int] = []  # client ports, in accept order
        self.turned_away = 0  # connections reset for another's session (``sessions``)
        self._open: list[socket.socket] = []
        self._sentinels: set[int] = set()
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._sock = socket.create_server((HOST, 0))
        self._sock.settimeout(0.05)
        self.port: int = self._sock.getsockname()[1]
        self._threads = [threading.Thread(target=self._accept_loop, daemon=True)]
        self._threads[0].start()

    @property
    def args(self) -> list[str]:
        return ["-H", HOST, "-p", str(self.port)]

    @property
    def accepted(self) -> int:
        """How many connections it accepted."""
        return len(self.peers)

    def _accept_loop(self) -> None:
        while not self._stop.is_set():
            try:
                conn, addr = self._sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            with self._cond:
                self.peers.append(addr[1])
                number = len(self.peers)
                self._cond.notify_all()
                if self._open and self.sessions == "one":
                    self.turned_away += 1
                    _reset(conn)
                    continue
                if self._open and self.sessions == "newest":  # the older is pushed out
                    self.turned_away += 1
                    for held in self._open:
                        _reset(held)
                self._open.append(conn)
            thread = threading.Thread(target=self._serve, args=(conn, number), daemon=True)
            self._threads.append(thread)
            thread.start()

    def _serve(self, conn: socket.socket, number: int) -> None:
        try:
            with conn:
                if self.answers != 0:
                    self._talk(conn, number)
        finally:
            with self._cond:
                if conn in self._open:
                    self._open.remove(conn)

    def _talk(self, conn: socket.socket, number: int) -> None:
        conn.settimeout(0.05)
        buffer = b""
        answered = 0
        while not self._stop.is_set():
            try:
                data = conn.recv(65536)
            except TimeoutError:
                continue
            except OSError:
                return
            if not data:
                return
            with self._cond:
                self.received += data
                self._cond.notify_all()
            buffer += data
            while b"\r" in buffer:
                line, _, buffer = buffer.partition(b"\r")
                with self._cond:
                    self.lines.append(line)
                    self.numbered.append((number, line))
                    self._cond.notify_all()
                answer = self.reply(line)
                if answer is CLOSE:
                    return
                if answer is RESET:
                    with contextlib.suppress(OSError):
                        conn.setsockopt(
                            socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0)
                        )
                    return
                if isinstance(answer, bytes) and answer:
                    try:
                        conn.sendall(answer)
                    except OSError:
                        return
                answered += 1
                if self.answers is not None and answered >= self.answers:
                    return

    def hang_up(self) -> None:
        """End every open connection now (a FIN), unasked."""
        with self._cond:
            conns = list(self._open)
        for conn in conns:
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)

    def connections(self) -> list[int]:
        """Every connection made before now (by anyone but this test's probes).

        A probe connection is opened and waited for: connections are accepted in
        the order they were made, so once the probe is accepted every earlier one is.
        """
        with socket.create_connection((HOST, self.port), timeout=5) as probe:
            port = probe.getsockname()[1]
            self._sentinels.add(port)
            with self._cond:
                assert self._cond.wait_for(lambda: port in self.peers, timeout=5)
                index = self.peers.index(port)
                return [p for p in self.peers[:index] if p not in self._sentinels]

    def wait_line(self, line: bytes, timeout: float = 10) -> bool:
        """Whether ``line`` (without its CR) came within ``timeout`` seconds: woken by
        each line that comes, never a sleep."""
        with self._cond:
            return self._cond.wait_for(lambda: line in self.lines, timeout=timeout)

    def wait_received(self, size: int, timeout: float = 5) -> bytes:
        with self._cond:
            self._cond.wait_for(lambda: len(self.received) >= size, timeout=timeout)
            return bytes(self.received)

    def close(self) -> None:
        self._stop.set()
        self._sock.close()
        for thread in self._threads:
            thread.join(timeout=2)


class Recording(Protocol):
    """The ``recording`` fixture: makes a :class:`RecordingServer` that stops with the test."""

    def __call__(
        self, reply: Reply = ..., *, sessions: Sessions = ..., answers: int | None = ...
    ) -> RecordingServer: ...


# ------------------------------------------------------------------ the valve


class Valve:
    """A TCP path from 127.0.0.1:``port`` to a server (the simulator) whose answers the
    test lets through: while :meth:`shut`, what the server sends waits (nothing is lost,
    nothing reordered); :meth:`open` sends it on. What the client sends always goes
    through. A reply is then in flight for exactly as long as the test says, whatever
    the load of the machine (a delay set on the simulator is a race with the test).
    :attr:`requests` counts the CR-terminated lines that went through to the server:
    what the controller was asked, counted at its side."""

    def __init__(self, host: str, port: int) -> None:
        self.host, self.port_to = host, port
        self.requests = 0
        self._counting = threading.Lock()
        self._open = threading.Event()
        self._open.set()
        self._ends: list[socket.socket] = []
        self._listener = socket.create_server((HOST, 0))
        self.port: int = self._listener.getsockname()[1]
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                client, _ = self._listener.accept()
            except OSError:  # closed
                return
            server = socket.create_connection((self.host, self.port_to), timeout=10)
            server.settimeout(None)
            self._ends += [client, server]
            threading.Thread(target=self._pump, args=(client, server, False), daemon=True).start()
            threading.Thread(target=self._pump, args=(server, client, True), daemon=True).start()

    def _pump(self, source: socket.socket, sink: socket.socket, held: bool) -> None:
        with contextlib.suppress(OSError):
            while data := source.recv(65536):
                if held:
                    self._open.wait()
                sink.sendall(data)
                if not held:
                    with self._counting:
                        self.requests += data.count(b"\r")
        for end in (sink, source):
            with contextlib.suppress(OSError):
                end.shutdown(socket.SHUT_RDWR)

    def shut(self) -> None:
        self._open.clear()

    def open(self) -> None:
        self._open.set()

    def close(self) -> None:
        self.open()
        self._listener.close()
        for end in self._ends:
            end.close()


# ------------------------------------------------------- the asyncio server

Handler = Callable[["Conn"], Awaitable[None]]


@dataclass
class Conn:
    """One accepted connection of a FaultServer, as its handler sees it."""

    server: FaultServer
    number: int
    reader: asyncio.StreamReader
    writer: asyncio.StreamWriter

    async def line(self) -> bytes:
        """One request line without its CR; IncompleteReadError at EOF."""
        line = (await self.reader.readuntil(b"\r"))[:-1]
        self.server.lines.append(line)
        return line

    async def send(self, data: bytes) -> None:
        self.writer.write(data)
        await self.writer.drain()


class FaultServer:
    """A TCP server on 127.0.0.1:0 on the running event loop, running ``handler(conn)``
    for each connection (``async with``)."""

    def __init__(self, handler: Handler) -> None:
        self.handler = handler
        self.connections = 0
        self.lines: list[bytes] = []
        self.ended: list[int] = []
        self._tasks: set[asyncio.Task[None]] = set()
        self._server: asyncio.Server | None = None
        self.port = 0

    async def __aenter__(self) -> FaultServer:
        self._server = await asyncio.start_server(self._serve, HOST, 0)
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def __aexit__(self, *exc_info: object) -> None:
        assert self._server is not None
        self._server.close()
        for task in list(self._tasks):
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        await self._server.wait_closed()

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        self.connections += 1
        conn = Conn(self, self.connections, reader, writer)
        try:
            await self.handler(conn)
        except (ConnectionError, asyncio.IncompleteReadError):
            pass
        finally:
            self.ended.append(conn.number)
            writer.close()
            self._tasks.discard(task)

    def session(self, **kwargs: object) -> AsyncSession:
        return AsyncSession(HOST, self.port, **kwargs)
