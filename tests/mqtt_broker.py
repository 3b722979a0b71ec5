"""A real mosquitto for the plant's tests, a subscriber that waits on what it saw, and
a CLI command left running whose lines are waited on.

The broker is Debian's ``mosquitto`` (installed by ``.ci/run`` where missing), started
here on 127.0.0.1 and a free port with a configuration of the test's own; a test that
needs it skips when it is not installed (the Windows lane: it is a Linux program).

Run as a script, ``python tests/mqtt_broker.py HOST PORT TOPIC`` is a subscriber that
prints what it gets as JSON lines (:func:`listen`): one that runs where the test itself
cannot reach the broker, in another network namespace.
"""

from __future__ import annotations

import contextlib
import getpass
import json
import queue
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest


def mosquitto_path() -> str | None:
    return shutil.which("mosquitto") or shutil.which("mosquitto", path="/usr/sbin:/usr/local/sbin")


needs_mosquitto = pytest.mark.skipif(
    mosquitto_path() is None, reason="mosquitto is not installed (.ci/run installs it)"
)


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

        self.messages: list[tuple[str, bytes, bool]] = []
        self.last: dict[str, bytes] = {}
        self._changed = threading.Condition()
        client = mqtt.Client(callback_api_version=mqtt.CallbackAPIVersion.VERSION2)
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


#: The CLI, as :class:`Running` starts it unless told another program.
RAC = (sys.executable, "-m", "rac_console")


class Running:
    """A CLI command left running: its stdout and stderr lines as they come."""

    def __init__(
        self,
        environment: dict[str, str],
        *args: str,
        wrap: Sequence[str] = (),
        program: Sequence[str] = RAC,
    ) -> None:
        """``program`` with ``args``, behind ``wrap`` when given (``ip netns exec B``:
        a command that runs it in place of itself, so that a signal reaches it)."""
        self.process = subprocess.Popen(
            [*wrap, *program, *args],
            env=environment,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            encoding="utf-8",
            errors="backslashreplace",
        )
        self.out: list[str] = []
        self.err: list[str] = []
        self._lines: queue.Queue[None] = queue.Queue()
        self._lock = threading.Lock()
        for stream, kept in ((self.process.stdout, self.out), (self.process.stderr, self.err)):
            threading.Thread(target=self._read, args=(stream, kept), daemon=True).start()

    def _read(self, stream: object, kept: list[str]) -> None:
        for line in stream:  # type: ignore[attr-defined]
            with self._lock:
                kept.append(line.rstrip("\n"))
            self._lines.put(None)

    def wait_for(self, what: str, holds: Callable[[], bool], deadline: float = 20) -> None:
        until = time.monotonic() + deadline
        while True:
            with self._lock:
                if holds():
                    return
            left = until - time.monotonic()
            if left <= 0 or (self.process.poll() is not None and self._lines.empty()):
                with self._lock:
                    if holds():
                        return
                raise AssertionError(f"timed out waiting for {what}:\n{self.out[-5:]}\n{self.err}")
            with contextlib.suppress(queue.Empty):
                self._lines.get(timeout=min(left, 0.5))

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                return self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
        return self.process.wait(20)


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

    def say(**fields: Any) -> None:
        print(json.dumps(fields), flush=True)

    def on_connect(client: Any, userdata: Any, flags: Any, reason: Any, properties: Any) -> None:
        say(connected=str(reason))
        client.subscribe(topic, qos=1)

    def on_message(client: Any, userdata: Any, message: Any) -> None:
        text = message.payload.decode("utf-8", "backslashreplace")
        say(topic=message.topic, payload=text, retain=bool(message.retain))

    client = mqtt.Client(callback_api_version=mqtt.CallbackAPIVersion.VERSION2)
    client.on_connect = on_connect
    client.on_message = on_message
    client.reconnect_delay_set(1, 1)
    client.connect_async(host, port, keepalive=30)
    with contextlib.suppress(KeyboardInterrupt):
        client.loop_forever(retry_first_connection=True)


if __name__ == "__main__":
    listen(sys.argv[1], int(sys.argv[2]), sys.argv[3])


# ------------------------------------------------------------------ fixtures
# Imported by the tests that use them (``from mqtt_broker import broker, ...``).


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[Broker]:
    """A mosquitto of the test's own, stopped with it."""
    started = Broker(tmp_path).start()
    try:
        yield started
    finally:
        started.stop()


@pytest.fixture
def subscriber(broker: Broker) -> Iterator[Subscriber]:
    """Subscribed to ``plant/#`` on the test's broker."""
    watching = Subscriber(broker.port, "plant/#")
    try:
        yield watching
    finally:
        watching.close()


@pytest.fixture
def running() -> Iterator[list[Running]]:
    """Commands a test leaves running: killed at its end if still there."""
    started: list[Running] = []
    yield started
    for command in started:
        if command.process.poll() is None:
            command.process.kill()
            command.process.wait(20)
