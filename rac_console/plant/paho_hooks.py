"""The private parts of paho-mqtt the feed leans on, all in this one module.

paho has no hook for what it reads, for why a connection attempt failed, or for how
long it waits before the next: the client here overrides six of its methods, for the
versions pyproject pins (``paho-mqtt>=2.0,<2.3``). ``tests/test_plant_guard.py`` fails
when any of them moves.

- ``_sock_recv``: every byte read goes through :class:`~.mqtt_guard.InboundGuard` first,
  and no read asks for more than :data:`~.mqtt_guard.CHUNK` bytes;
- ``_create_socket`` / ``_ssl_wrap_socket``: the reason of a failed attempt, and whether
  it failed at TLS, kept for the line that says it;
- ``_send_pingreq``: the guard takes only as many ping answers as pings went out (a
  broker may shorten the keepalive in its CONNACK: paho then pings more often);
- ``_reconnect_wait``: a backoff that a broker which connects and then misbehaves does
  not reset (paho starts again from the shortest wait after every CONNACK);
- ``_thread_main``: what paho does not catch ends publishing with one line, never a
  traceback on the user's terminal.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from types import ModuleType
from typing import Any

from .mqtt_guard import CHUNK, InboundGuard

#: The private names used, checked by the tests against the installed paho.
PRIVATE = (
    "_sock_recv", "_create_socket", "_ssl_wrap_socket", "_reconnect_wait", "_thread_main",
    "_send_pingreq", "_thread_terminate", "_state",
)  # fmt: skip


class Backoff:
    """Seconds between connection attempts: doubling from ``first`` to ``most``, back
    to ``first`` only once a connection has proved good (:meth:`good`)."""

    def __init__(self, first: float, most: float) -> None:
        self.first, self.most = first, most
        self.next = first
        self._stop = threading.Event()

    def good(self) -> None:
        self.next = self.first

    def wait(self, stopping: Callable[[], bool]) -> None:
        """Sleep the next delay (waking for ``stopping``), then double it."""
        delay, self.next = self.next, min(self.next * 2, self.most)
        waited = 0.0
        while waited < delay and not stopping() and not self._stop.is_set():
            step = min(0.25, delay - waited)
            self._stop.wait(step)
            waited += step

    def stop(self) -> None:
        self._stop.set()


@functools.cache
def _client_class(mqtt: ModuleType) -> type[Any]:
    class GuardedClient(mqtt.Client):  # type: ignore[misc,name-defined]
        """paho's client, guarded (see the module)."""

        rac_guard: InboundGuard
        rac_backoff: Backoff
        rac_crashed: Callable[[Exception], None]
        rac_failure: OSError | None = None  # why the last attempt failed
        rac_at_tls = False  # it failed in the TLS handshake

        def _sock_recv(self, bufsize: int) -> bytes:
            data: bytes = super()._sock_recv(min(bufsize, CHUNK))
            self.rac_guard.take(data)
            return data

        def _create_socket(self) -> Any:
            self.rac_failure, self.rac_at_tls = None, False
            try:
                sock = super()._create_socket()
            except OSError as exc:
                self.rac_failure = exc
                raise
            self.rac_guard.new_connection()
            return sock

        def _send_pingreq(self) -> Any:
            self.rac_guard.pinged()  # before it goes: its answer may come at once
            return super()._send_pingreq()

        def _ssl_wrap_socket(self, tcp_sock: Any) -> Any:
            self.rac_at_tls = True
            return super()._ssl_wrap_socket(tcp_sock)

        def _reconnect_wait(self) -> None:
            disconnecting = (
                mqtt._ConnectionState.MQTT_CS_DISCONNECTING,
                mqtt._ConnectionState.MQTT_CS_DISCONNECTED,
            )
            self.rac_backoff.wait(
                lambda: bool(self._thread_terminate) or self._state in disconnecting
            )

        def _thread_main(self) -> None:
            try:
                super()._thread_main()
            except Exception as exc:  # a name the resolver refuses, a topic paho cannot pack
                self.rac_crashed(exc)

    return GuardedClient


def guarded_client(
    mqtt: ModuleType,
    client_id: str,
    guard: InboundGuard,
    backoff: Backoff,
    crashed: Callable[[Exception], None],
) -> Any:
    """A paho MQTT 5 client whose reads go through ``guard``, whose waits between
    attempts are ``backoff``'s, and whose network thread calls ``crashed`` rather than
    raise."""
    client = _client_class(mqtt)(
        callback_api_version=mqtt.CallbackAPIVersion.VERSION2,
        client_id=client_id,
        protocol=mqtt.MQTTv5,
    )
    client.rac_guard, client.rac_backoff, client.rac_crashed = guard, backoff, crashed
    return client
