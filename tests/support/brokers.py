"""The brokers of the plant's tests: a real mosquitto, a subscriber that waits on what
it saw, a TCP path to a broker that can be pulled, and brokers that lie.

The broker is Debian's ``mosquitto`` (installed by ``.ci/run`` where missing), started
here on 127.0.0.1 and a free port with a configuration of the test's own; a test that
needs it skips when it is not installed (the Windows lane: it is a Linux program;
``needs_mosquitto`` in :mod:`tests.support.fixtures`).

Run as a script, ``python tests/support/brokers.py HOST PORT TOPIC`` is a subscriber
that prints what it gets as JSON lines (:func:`listen`): one that runs where the test
itself cannot reach the broker, in another network namespace. So this module imports
nothing of the tests' own.

Brokers that lie (also for ``benchmarks/plant_doors.py`` and ``scripts/screenshots.py``):
each reads the CONNECT, then does one hostile thing until the client hangs up.

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
import getpass
import json
import shutil
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any


def mosquitto_path() -> str | None:
    return shutil.which("mosquitto") or shutil.which("mosquitto", path="/usr/sbin:/usr/local/sbin")


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


class Broker:
    """mosquitto on ``host``:``port``: :meth:`start`, :meth:`stop`, start again on the
    same port (a restart loses its retained messages: persistence is off)."""

    def __init__(
        self,
        folder: Path,
        lines: tuple[str, ...] = ("allow_anonymous true",),
        host: str = "127.0.0.1",
    ) -> None:
        """``host``: the address it listens on (another namespace's, for a test that
        starts it there from :meth:`write_config`)."""
        self.folder = folder
        self.lines = lines
        self.host = host
        self.port = free_port()
        self.process: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"mqtt://{self.host}:{self.port}"

    def write_config(self) -> Path:
        """Its configuration file: listening on ``host:port``, no persistence."""
        config = self.folder / "mosquitto.conf"
        config.write_text(
            "\n".join(
                (
                    f"listener {self.port} {self.host}",
                    "persistence false",
                    f"user {getpass.getuser()}",  # it reads the test's files as the test
                    *self.lines,
                    "",
                )
            )
        )
        return config

    def start(self, deadline: float = 10.0) -> Broker:
        path = mosquitto_path()
        assert path is not None
        config = self.write_config()
        log = (self.folder / "mosquitto.log").open("ab")
        self.process = subprocess.Popen(
            [path, "-c", str(config)], stdout=log, stderr=subprocess.STDOUT
        )
        log.close()
        until = time.monotonic() + deadline
        while True:
            if self.process.poll() is not None:
                raise AssertionError(
                    f"mosquitto ended: {(self.folder / 'mosquitto.log').read_text()}"
                )
            try:
                socket.create_connection((self.host, self.port), timeout=0.5).close()
                return self
            except OSError:
                if time.monotonic() > until:
                    raise AssertionError("mosquitto did not listen in time") from None
                time.sleep(0.05)

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(10)
        self.process = None


class Subscriber:
    """A paho client subscribed to ``topic``: every message kept, in order, and the
    last of each topic; :meth:`wait_for` waits on a condition with a deadline."""

    def __init__(self, port: int, topic: str = "#", user: tuple[str, str] | None = None) -> None:
        import paho.mqtt.client as mqtt
        from paho.mqtt.enums import CallbackAPIVersion

        self.messages: list[tuple[str, bytes, bool]] = []
        self.last: dict[str, bytes] = {}
        self._changed = threading.Condition()
        client = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
        client.on_message = self._on_message
        client.on_connect = lambda c, u, f, r, p: c.subscribe(topic, qos=1)
        if user is not None:
            client.username_pw_set(*user)
        client.connect("127.0.0.1", port, keepalive=30)
        client.loop_start()
        self.client = client

    def _on_message(self, client: Any, userdata: Any, message: Any) -> None:
        with self._changed:
            self.messages.append((message.topic, message.payload, bool(message.retain)))
            self.last[message.topic] = message.payload
            self._changed.notify_all()

    def wait_for(
        self, what: str, holds: Callable[[Subscriber], bool], deadline: float = 15
    ) -> None:
        with self._changed:
            if not self._changed.wait_for(lambda: holds(self), deadline):
                shown = "\n".join(f"{t} {p!r}" for t, p, _ in self.messages[-20:])
                raise AssertionError(f"timed out waiting for {what}; last messages:\n{shown}")

    def value(self, topic: str) -> Any:
        """The ``value`` of the last JSON payload on ``topic`` (KeyError: none came)."""
        return json.loads(self.last[topic])["value"]

    def has_value(self, topic: str, value: Any) -> Callable[[Subscriber], bool]:
        def holds(sub: Subscriber) -> bool:
            payload = sub.last.get(topic)
            return (
                payload is not None
                and payload[:1] == b"{"
                and json.loads(payload)["value"] == value
            )

        return holds

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


class Cable:
    """A TCP path from 127.0.0.1:``port`` to a broker, which can be pulled.

    Pulled, the connections through it swallow what either side sends (nothing comes
    back, nothing is closed) and a new connection waits; :meth:`cut` then closes the
    swallowing ones, as each side's keepalive would in the end; :meth:`restore` lets
    new connections through again. What was swallowed is kept in :attr:`swallowed`.
    """

    def __init__(self, broker_port: int) -> None:
        self.broker_port = broker_port
        self.swallowed = b""
        self._lock = threading.Lock()
        self._open = threading.Event()
        self._open.set()
        self._live: list[tuple[socket.socket, socket.socket, threading.Event]] = []
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = int(self._listener.getsockname()[1])
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                client, _ = self._listener.accept()
            except OSError:  # closed
                return
            self._open.wait()
            upstream = socket.create_connection(("127.0.0.1", self.broker_port), timeout=10)
            upstream.settimeout(None)
            dead = threading.Event()
            with self._lock:
                self._live.append((client, upstream, dead))
            for source, sink in ((client, upstream), (upstream, client)):
                threading.Thread(target=self._pump, args=(source, sink, dead), daemon=True).start()

    def _pump(self, source: socket.socket, sink: socket.socket, dead: threading.Event) -> None:
        with contextlib.suppress(OSError):
            while data := source.recv(65536):
                if dead.is_set():
                    with self._lock:
                        self.swallowed += data
                else:
                    sink.sendall(data)

    def pull(self) -> None:
        self._open.clear()
        with self._lock:
            for _, _, dead in self._live:
                dead.set()

    def cut(self) -> None:
        with self._lock:
            cut = [(a, b) for a, b, dead in self._live if dead.is_set()]
            self._live = [live for live in self._live if not live[2].is_set()]
        for ends in cut:
            for end in ends:
                with contextlib.suppress(OSError):
                    end.shutdown(socket.SHUT_RDWR)
                end.close()

    def restore(self) -> None:
        self._open.set()

    def close(self) -> None:
        self.pull()
        self.cut()
        self._listener.close()
        self.restore()


def listen(host: str, port: int, topic: str) -> None:
    """Subscribe to ``topic`` on ``host:port`` and print, as JSON lines, each connection
    (``{"connected": REASON}``) and each message (``{"topic", "payload", "retain"}``, the
    payload as UTF-8 text), until interrupted or killed. Until the broker listens it
    tries again every second."""
    import paho.mqtt.client as mqtt
    from paho.mqtt.enums import CallbackAPIVersion

    def say(**fields: Any) -> None:
        print(json.dumps(fields), flush=True)

    def on_connect(client: Any, userdata: Any, flags: Any, reason: Any, properties: Any) -> None:
        say(connected=str(reason))
        client.subscribe(topic, qos=1)

    def on_message(client: Any, userdata: Any, message: Any) -> None:
        text = message.payload.decode("utf-8", "backslashreplace")
        say(topic=message.topic, payload=text, retain=bool(message.retain))

    client = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
    client.on_connect = on_connect
    client.on_message = on_message
    client.reconnect_delay_set(1, 1)
    client.connect_async(host, port, keepalive=30)
    with contextlib.suppress(KeyboardInterrupt):
        client.loop_forever(retry_first_connection=True)


# ------------------------------------------------------------ brokers that lie

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


if __name__ == "__main__":
    listen(sys.argv[1], int(sys.argv[2]), sys.argv[3])
