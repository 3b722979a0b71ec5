"""Brokers that lie, written for the tests (and ``benchmarks/plant_doors.py``): each
reads the CONNECT, then does one hostile thing until the client hangs up.

- ``a 256 MB CONNACK``: a CONNACK whose length says 256 MB, then zeros without end;
- ``a CONNACK, then junk``: every byte value, without end;
- ``a CONNACK, then a PUBACK storm``: acknowledgements of a message never sent;
- ``a CONNACK, then silence``: what the client sends is read and never answered;
- ``a CONNACK, then a packet dripped``: a PUBACK of 64 KiB, a byte every 0.2 s;
- ``an ack, then a PUBLISH never asked for``: honest, until the first acknowledgement;

and one that does nothing wrong (``HONEST``): a Server Keep Alive of 1 s in its CONNACK.

Each keeps when its connections came and how many the client hung up on.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Callable

CONNACK = bytes((0x20, 3, 0, 0, 0))  # MQTT 5: no session, success, no properties
#: 256 MB announced: the most a 4-byte remaining length can say.
HUGE_CONNACK = bytes((0x20, 0xFF, 0xFF, 0xFF, 0x7F))


class HostileBroker:
    """Accepts MQTT connections on 127.0.0.1; each gets ``act(conn)`` after its CONNECT.
    Keeps when each connection came and whether the client hung up on it."""

    def __init__(self, name: str, act: Callable[[socket.socket], None]) -> None:
        self.name, self._act = name, act
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port: int = self._server.getsockname()[1]
        self.connections: list[float] = []  # monotonic times
        self.hung_up = 0  # connections the client closed while the broker still sent
        self.pings = 0  # PINGREQs answered (by the honest ones)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._threads = [threading.Thread(target=self._accept, daemon=True)]
        self._threads[0].start()

    def _accept(self) -> None:
        self._server.settimeout(0.2)
        while not self._stop.is_set():
            try:
                conn, _ = self._server.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            with self._lock:
                self.connections.append(time.monotonic())
            worker = threading.Thread(target=self._serve, args=(conn,), daemon=True)
            self._threads.append(worker)
            worker.start()

    def _serve(self, conn: socket.socket) -> None:
        with conn:
            conn.settimeout(10)
            try:
                read_packet(conn)  # the CONNECT
                self._act(conn)
            except (ConnectionError, BrokenPipeError):
                with self._lock:
                    self.hung_up += 1
            except OSError:
                pass

    @property
    def stopping(self) -> bool:
        return self._stop.is_set()

    def wait(self, seconds: float) -> None:
        """Pace a broker's own sending (ends at once when the test ends)."""
        self._stop.wait(seconds)

    def count(self) -> tuple[int, int]:
        with self._lock:
            return len(self.connections), self.hung_up

    def close(self) -> None:
        self._stop.set()
        self._server.close()
        for thread in self._threads:
            thread.join(5)


def read_packet(conn: socket.socket) -> bytes:
    header = conn.recv(1)
    if not header:
        raise ConnectionError("closed")
    length, shift = 0, 0
    while True:
        byte = conn.recv(1)
        if not byte:
            raise ConnectionError("closed")
        length += (byte[0] & 0x7F) << shift
        shift += 7
        if not byte[0] & 0x80:
            break
    body = b""
    while len(body) < length:
        chunk = conn.recv(length - len(body))
        if not chunk:
            raise ConnectionError("closed")
        body += chunk
    return header + body


def streaming(
    first: bytes, then: Callable[[int], bytes]
) -> Callable[[HostileBroker], Callable[[socket.socket], None]]:
    """A broker that sends ``first`` and then ``then(n)`` for n = 0, 1, … until the client
    hangs up (a ConnectionError: counted) or the test ends."""

    def make(broker: HostileBroker) -> Callable[[socket.socket], None]:
        def act(conn: socket.socket) -> None:
            conn.sendall(first)
            n = 0
            while not broker.stopping:
                conn.sendall(then(n))
                n += 1

        return act

    return make


def silent(broker: HostileBroker) -> Callable[[socket.socket], None]:
    """CONNACK, then nothing: what the client sends is read and never answered."""

    def act(conn: socket.socket) -> None:
        conn.sendall(CONNACK)
        conn.settimeout(0.2)
        while not broker.stopping:
            with contextlib.suppress(TimeoutError):
                if not conn.recv(65536):
                    raise ConnectionError("the client hung up")

    return act


def answering(
    connack: bytes, after: Callable[[int], bytes | None] = lambda n: None
) -> Callable[[HostileBroker], Callable[[socket.socket], None]]:
    """A broker that answers as MQTT 5 asks (a PUBACK for each QoS 1 PUBLISH, a PINGRESP
    for each PINGREQ), after ``connack``; after the ``n``-th PUBLISH it also sends
    ``after(n)`` when that is not None. It counts the pings it answered."""

    def make(broker: HostileBroker) -> Callable[[socket.socket], None]:
        def act(conn: socket.socket) -> None:
            conn.sendall(connack)
            published = 0
            conn.settimeout(0.2)
            while not broker.stopping:
                try:
                    packet = read_packet(conn)
                except TimeoutError:
                    continue
                kind = packet[0] >> 4
                if kind == 12:  # PINGREQ
                    conn.sendall(bytes((0xD0, 0)))
                    broker.pings += 1
                elif kind == 3 and (packet[0] >> 1) & 3:  # a PUBLISH to acknowledge
                    body = packet[1:]
                    topic = int.from_bytes(body[:2], "big")
                    conn.sendall(bytes((0x40, 2)) + body[2 + topic : 4 + topic])
                    published += 1
                    if (extra := after(published)) is not None:
                        conn.sendall(extra)
                elif kind == 14:  # DISCONNECT
                    return

        return act

    return make


def dripping(broker: HostileBroker) -> Callable[[socket.socket], None]:
    """CONNACK, then a PUBACK announced at 64 KiB, sent a byte every 0.2 s."""

    def act(conn: socket.socket) -> None:
        conn.sendall(CONNACK + bytes((0x40, 0x80, 0x80, 0x04)))
        while not broker.stopping:
            conn.sendall(b"\0")
            broker.wait(0.2)

    return act


#: A CONNACK whose Server Keep Alive (property 0x13) is 1 s: the client must ping so.
SHORT_KEEPALIVE_CONNACK = bytes((0x20, 6, 0, 0, 3, 0x13, 0, 1))
#: A PUBLISH to a client that never subscribed.
UNASKED_PUBLISH = bytes((0x30, 5, 0, 1, ord("x"), 0)) + b"!"

JUNK = bytes(range(256)) * 256  # 64 KiB, every byte value
STORM = bytes((0x40, 2, 0x12, 0x34)) * 16_384  # 16,384 PUBACKs of a message never sent

HOSTILE = {
    "a 256 MB CONNACK": streaming(HUGE_CONNACK, lambda n: bytes(65_536)),
    "a CONNACK, then junk": streaming(CONNACK, lambda n: JUNK[n % 256 :] + JUNK[: n % 256]),
    "a CONNACK, then a PUBACK storm": streaming(CONNACK, lambda n: STORM),
    "a CONNACK, then silence": silent,
    "a CONNACK, then a packet dripped": dripping,
    "an ack, then a PUBLISH never asked for": answering(
        CONNACK, lambda n: UNASKED_PUBLISH if n == 1 else None
    ),
}
#: Brokers that do nothing wrong, for the same tests: nothing may be said of them.
HONEST = {
    "honest, with a 1 s Server Keep Alive": answering(SHORT_KEEPALIVE_CONNACK),
}


def hostile_broker(name: str) -> HostileBroker:
    """One of :data:`HOSTILE`, listening."""
    holder: list[Callable[[socket.socket], None]] = []
    broker = HostileBroker(name, lambda conn: holder[0](conn))
    holder.append((HOSTILE | HONEST)[name](broker))
    return broker
