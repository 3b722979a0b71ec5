"""``/metrics`` over HTTP with bounds: one thread, whatever the scrapers do.

prometheus-client's own server gives every connection a thread and waits on it without
a timeout: 1,500 idle connections made 1,503 threads and 429 MB, and four scrapers
asking flat out cut polling to a quarter. Here one thread serves every connection from
a selector:

- at most :data:`MOST_CONNECTIONS` at once; beyond that the listening socket is not
  read, and new connections wait in the kernel's queue;
- a request's head must arrive within :data:`HEAD_TIMEOUT` seconds and fit in
  :data:`MOST_HEAD` bytes, the response be taken within :data:`SEND_TIMEOUT`;
- the page is made from the board at most once per :data:`FRESH_FOR` seconds (per
  format) and the same bytes go to every scrape in that time;
- at most :data:`MOST_PER_SECOND` responses a second: a scraper asking faster waits.

A scrape thus costs the polling a bounded share however many ask and however often.
prometheus-client still makes the page (the text format, or OpenMetrics when asked).
"""

from __future__ import annotations

import contextlib
import errno
import selectors
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ..commands.plant import MetricsAddress
from ..protocol import InputError
from .extras import need

MOST_CONNECTIONS = 256
#: Seconds the listener rests when the process is out of descriptors (accept fails).
DESCRIPTORS_REST = 0.5
HEAD_TIMEOUT = 3.0
SEND_TIMEOUT = 10.0
MOST_HEAD = 8192
FRESH_FOR = 1.0
MOST_PER_SECOND = 20
#: Responses that may go at once after a quiet spell (the token bucket's depth).
BURST = 5
_PATHS = ("/metrics", "/")
#: The two pages: the text format, and OpenMetrics for a scraper that asks for it. Fixed
#: content types: nothing of a request's Accept header is ever written back.
TEXT, OPENMETRICS = (
    "text/plain; version=0.0.4; charset=utf-8",
    ("application/openmetrics-text; version=1.0.0; charset=utf-8"),
)


@dataclass
class _Connection:
    sock: socket.socket
    deadline: float
    head: bytearray = field(default_factory=bytearray)
    out: memoryview | None = None  # the response, from what is left to send
    waiting: bytes | None = None  # the Accept header of a request waiting for its turn
    head_only: bool = False
    done: bool = False  # answered: what the client still sends is read and dropped


class MetricsServer:
    """Serves a board's ``/metrics`` on a thread of its own until :meth:`stop`."""

    def __init__(self, address: MetricsAddress, board: Any) -> None:
        """InputError when the extra is missing or the address cannot be served."""
        client = need("prometheus_client", "--metrics")
        from prometheus_client.exposition import generate_latest
        from prometheus_client.openmetrics.exposition import generate_latest as openmetrics

        self._encoders: dict[str, Callable[[Any], bytes]] = {
            TEXT: generate_latest,
            OPENMETRICS: openmetrics,
        }
        self._registry = client.CollectorRegistry(auto_describe=False)
        self._registry.register(board)
        try:
            self._listener = _listen(address)
        except (OSError, OverflowError, UnicodeError) as exc:
            why = getattr(exc, "strerror", None) or str(exc)
            raise InputError(f"--metrics cannot serve {address}: {why}") from None
        self._listener.setblocking(False)
        self.address = address
        self.port: int = self._listener.getsockname()[1]
        self._selector = selectors.DefaultSelector()
        self._waker, self._wake = socket.socketpair()
        for end in (self._waker, self._wake):
            end.setblocking(False)
        self._selector.register(self._waker, selectors.EVENT_READ, None)
        self._listening = False
        self._rest_until = 0.0  # out of descriptors: the listener rests until then
        self._most = _most_connections()
        self._connections: dict[socket.socket, _Connection] = {}
        self._pages: dict[str, tuple[float, bytes]] = {}  # content type: made at, body
        self._tokens, self._filled_at = float(BURST), time.monotonic()
        self._stopping = False
        self.served = 0  # responses sent (the benchmark's figure)
        self._thread = threading.Thread(target=self._serve, name="rac-metrics", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stopping = True
        with contextlib.suppress(OSError):
            self._wake.send(b"x")
        self._thread.join(5)
        for sock in [*self._connections, self._listener, self._waker, self._wake]:
            sock.close()
        self._selector.close()

    # ------------------------------------------------------------ the server's thread

    def _serve(self) -> None:
        while not self._stopping:
            now = time.monotonic()
            self._listen(len(self._connections) < self._most and now >= self._rest_until)
            for key, mask in self._selector.select(self._rest()):
                if key.fileobj is self._listener:
                    self._accept()
                elif key.fileobj is self._waker:
                    with contextlib.suppress(OSError):
                        self._waker.recv(64)
                else:
                    self._serve_one(key.data, mask)
            self._expire()
            self._answer_waiting()

    def _serve_one(self, connection: _Connection, mask: int) -> None:
        """One connection's turn: whatever goes wrong with it ends it, never the server."""
        try:
            if mask & selectors.EVENT_READ:
                self._read(connection)
            else:
                self._send(connection)
        except Exception:  # a request no one foresaw: that connection goes, the rest stay
            self._close(connection)

    def _listen(self, room: bool) -> None:
        if room and not self._listening:
            self._selector.register(self._listener, selectors.EVENT_READ, None)
        elif not room and self._listening:
            self._selector.unregister(self._listener)
        self._listening = room

    def _rest(self) -> float:
        """Seconds until a deadline passes or a waiting request's turn comes."""
        now = time.monotonic()
        soonest = min((c.deadline for c in self._connections.values()), default=now + 1.0)
        if now < self._rest_until:
            soonest = min(soonest, self._rest_until)
        if any(c.waiting is not None for c in self._connections.values()):
            soonest = min(soonest, now + max(0.0, (1 - self._tokens) / MOST_PER_SECOND))
        return max(0.0, soonest - now)

    def _accept(self) -> None:
        while len(self._connections) < self._most:
            try:
                sock, _ = self._listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:  # out of descriptors, or a connection reset in the queue
                if exc.errno in (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM):
                    self._rest_until = time.monotonic() + DESCRIPTORS_REST  # or it spins
                return
            sock.setblocking(False)
            connection = _Connection(sock, time.monotonic() + HEAD_TIMEOUT)
            self._connections[sock] = connection
            self._selector.register(sock, selectors.EVENT_READ, connection)

    def _read(self, connection: _Connection) -> None:
        try:
            data = connection.sock.recv(4096)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            data = b""
        if not data:
            self._close(connection)
            return
        if connection.done:
            return  # a lingering close: the answer is not lost to a reset
        connection.head += data
        end = connection.head.find(b"\r\n\r\n")
        if end > MOST_HEAD or (end < 0 and len(connection.head) > MOST_HEAD):
            connection.done = True  # read no more of it
            self._respond(connection, 431, b"request head too large\n")
            return
        if end < 0:
            return
        self._selector.unregister(connection.sock)  # nothing more is read from it
        self._request(connection, bytes(connection.head[:end]))

    def _request(self, connection: _Connection, head: bytes) -> None:
        lines = head.split(b"\r\n")
        words = lines[0].split(b" ")
        if len(words) != 3 or not words[2].startswith(b"HTTP/1."):
            self._respond(connection, 400, b"not an HTTP/1 request\n")
            return
        method, target = words[0], words[1].split(b"?", 1)[0].decode("latin-1")
        if method not in (b"GET", b"HEAD"):
            self._respond(connection, 405, b"GET /metrics\n", extra=b"Allow: GET, HEAD\r\n")
            return
        if target not in _PATHS:
            self._respond(connection, 404, b"the values are at /metrics\n")
            return
        accept = b""
        for line in lines[1:]:
            name, _, value = line.partition(b":")
            if name.strip().lower() == b"accept":
                accept = value.strip()
        connection.waiting, connection.head_only = accept, method == b"HEAD"
        connection.deadline = time.monotonic() + SEND_TIMEOUT

    def _answer_waiting(self) -> None:
        """Answer the requests waiting, as far as the rate allows, oldest first."""
        now = time.monotonic()
        self._tokens = min(BURST, self._tokens + (now - self._filled_at) * MOST_PER_SECOND)
        self._filled_at = now
        for connection in list(self._connections.values()):
            if connection.waiting is None:
                continue
            if self._tokens < 1:
                return
            self._tokens -= 1
            try:
                content_type, body = self._page(connection.waiting.decode("latin-1"), now)
            except Exception:  # the page could not be made: said as such, the server goes on
                content_type, body = "text/plain; charset=utf-8", b"the page failed\n"
                self._pages.clear()
            connection.waiting = None
            self._respond(
                connection,
                200,
                b"" if connection.head_only else body,
                content_type=content_type,
                length=len(body),
            )

    def _page(self, accept: str, now: float) -> tuple[str, bytes]:
        """OpenMetrics when ``accept`` names it, else the text format: one of two pages,
        each made again only when older than :data:`FRESH_FOR`."""
        content_type = OPENMETRICS if "application/openmetrics-text" in accept else TEXT
        made = self._pages.get(content_type)
        if made is None or now - made[0] >= FRESH_FOR:
            made = (now, self._encoders[content_type](self._registry))
            self._pages[content_type] = made
        return content_type, made[1]

    def _respond(
        self,
        connection: _Connection,
        status: int,
        body: bytes,
        *,
        content_type: str = "text/plain; charset=utf-8",
        length: int | None = None,
        extra: bytes = b"",
    ) -> None:
        reason = _REASONS.get(status, "Error")
        head = (
            f"HTTP/1.1 {status} {reason}\r\nContent-Type: {content_type}\r\n"
            f"Content-Length: {len(body) if length is None else length}\r\n"
            "Connection: close\r\nCache-Control: no-store\r\n"
            "X-Content-Type-Options: nosniff\r\n"
        ).encode("latin-1")
        connection.out = memoryview(head + extra + b"\r\n" + body)
        connection.deadline = time.monotonic() + SEND_TIMEOUT
        try:
            self._selector.modify(connection.sock, selectors.EVENT_WRITE, connection)
        except KeyError:  # unregistered while it waited for its turn
            self._selector.register(connection.sock, selectors.EVENT_WRITE, connection)

    def _send(self, connection: _Connection) -> None:
        if connection.out is None:
            return
        try:
            sent = connection.sock.send(connection.out)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._close(connection)
            return
        connection.out = connection.out[sent:]
        if not connection.out:
            self.served += 1
            try:
                connection.sock.shutdown(socket.SHUT_WR)
            except OSError:
                self._close(connection)
                return
            # Closed with unread bytes, the kernel would reset the connection and the
            # answer might be lost: read until the client closes (or the deadline).
            connection.out, connection.done = None, True
            connection.deadline = time.monotonic() + HEAD_TIMEOUT
            self._selector.modify(connection.sock, selectors.EVENT_READ, connection)

    def _expire(self) -> None:
        now = time.monotonic()
        for connection in [c for c in self._connections.values() if c.deadline <= now]:
            self._close(connection)

    def _close(self, connection: _Connection) -> None:
        self._connections.pop(connection.sock, None)
        with contextlib.suppress(KeyError, ValueError):
            self._selector.unregister(connection.sock)
        connection.sock.close()


def _listen(address: MetricsAddress) -> socket.socket:
    """The listening socket: the family the address resolves to; ``::`` takes IPv4 too
    where the system can (as prometheus-client's server did)."""
    family = socket.getaddrinfo(address.host, address.port, type=socket.SOCK_STREAM)[0][0]
    both = family == socket.AF_INET6 and address.host in ("::", "") and socket.has_dualstack_ipv6()
    return socket.create_server(
        (address.host, address.port), family=family, backlog=64, dualstack_ipv6=both
    )


def _most_connections() -> int:
    """:data:`MOST_CONNECTIONS`, or fewer where the process may open few descriptors (a
    quarter of them: the controllers' and the broker's sockets need the rest)."""
    try:
        import resource
    except ImportError:  # Windows: select() takes 512 sockets; 256 leave room
        return MOST_CONNECTIONS
    soft, _ = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft == resource.RLIM_INFINITY:
        return MOST_CONNECTIONS
    return max(8, min(MOST_CONNECTIONS, soft // 4))


_REASONS = {
    200: "OK",
    400: "Bad Request",
    404: "Not Found",
    405: "Method Not Allowed",
    431: "Request Header Fields Too Large",
}
