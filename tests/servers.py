"""Servers written for the tests: every one binds 127.0.0.1 port 0 and stops with the test."""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Callable


class _Close:
    """A reply that closes the connection instead of answering."""


CLOSE = _Close()

Reply = Callable[[bytes], "bytes | _Close | None"]


class Answering:
    """A reply that can be changed while the server runs (``None``: stay silent)."""

    def __init__(self, answer: bytes | _Close | None = None) -> None:
        self.answer = answer

    def __call__(self, line: bytes) -> bytes | _Close | None:
        return self.answer


class RecordingServer:
    """A TCP server on 127.0.0.1:0 in background threads.

    It records every byte received and the order connections were accepted in,
    and answers each CR-terminated line with ``reply(line)`` (None: no answer).
    """

    def __init__(self, reply: Reply) -> None:
        self.reply = reply
        self.received = bytearray()
        self.lines: list[bytes] = []
        self.peers: list[int] = []  # client ports, in accept order
        self._sentinels: set[int] = set()
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._sock = socket.create_server(("127.0.0.1", 0))
        self._sock.settimeout(0.05)
        self.port: int = self._sock.getsockname()[1]
        self._threads = [threading.Thread(target=self._accept_loop, daemon=True)]
        self._threads[0].start()

    @property
    def args(self) -> list[str]:
        return ["-H", "127.0.0.1", "-p", str(self.port)]

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
                self._cond.notify_all()
            thread = threading.Thread(target=self._serve, args=(conn,), daemon=True)
            self._threads.append(thread)
            thread.start()

    def _serve(self, conn: socket.socket) -> None:
        conn.settimeout(0.05)
        buffer = b""
        with conn:
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
                    self.lines.append(line)
                    answer = self.reply(line)
                    if answer is CLOSE:
                        return
                    if answer:
                        try:
                            conn.sendall(answer)
                        except OSError:
                            return

    def connections(self) -> list[int]:
        """Every connection made before now (by anyone but this test's probes).

        A probe connection is opened and waited for: connections are accepted in
        the order they were made, so once the probe is accepted every earlier one is.
        """
        with socket.create_connection(("127.0.0.1", self.port), timeout=5) as probe:
            port = probe.getsockname()[1]
            self._sentinels.add(port)
            with self._cond:
                assert self._cond.wait_for(lambda: port in self.peers, timeout=5)
                index = self.peers.index(port)
                return [p for p in self.peers[:index] if p not in self._sentinels]

    def wait_received(self, size: int, timeout: float = 5) -> bytes:
        with self._cond:
            self._cond.wait_for(lambda: len(self.received) >= size, timeout=timeout)
            return bytes(self.received)

    def close(self) -> None:
        self._stop.set()
        self._sock.close()
        for thread in self._threads:
            thread.join(timeout=2)


class Valve:
    """A TCP path from 127.0.0.1:``port`` to a server (the simulator) whose answers the
    test lets through: while :meth:`shut`, what the server sends waits (nothing is lost,
    nothing reordered); :meth:`open` sends it on. What the client sends always goes
    through. A reply is then in flight for exactly as long as the test says, whatever
    the load of the machine (a delay set on the simulator is a race with the test)."""

    def __init__(self, host: str, port: int) -> None:
        self.host, self.port_to = host, port
        self._open = threading.Event()
        self._open.set()
        self._ends: list[socket.socket] = []
        self._listener = socket.create_server(("127.0.0.1", 0))
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
