"""One target's watched values to an MQTT broker: retained topics, QoS 1, a last will.

Each target has its own connection, so that its ``PREFIX/<target>/status`` topic has a
last will of its own (``offline``, retained): a console killed, a cable pulled, and the
plant sees that target's values are no longer live.

Polling never waits on the broker. The engine's thread only puts the latest reading of a
topic in a dict (:meth:`MqttFeed.update_many`); a thread of the feed's own makes the
payload and hands it to paho-mqtt, at most :data:`IN_FLIGHT` unacknowledged at a time,
and paho's thread does the network. A topic gets a message at most every :data:`EVERY`
seconds, always its latest reading: a value that changes at every poll of a fast
controller would otherwise take the interpreter from polling (paho spends tens of
microseconds on a message), and a dashboard reads no faster. A change after a quiet
spell goes at once; a change within the pace goes at its end, so an I/O pulse shows
both its edges. While the broker is away the dict keeps the latest payload of every topic, so
memory stays bounded whatever the outage; when it is back, every topic is published
again (a broker that restarted without persistence has lost its retained messages).
paho also sends again what it had sent unacknowledged (a cable pulled: gone into the
void), in no set order with those: an older value the broker takes after the latest of
its topic is followed by the latest again, so that the latest is what stays retained.
Each trouble is said once, and its end once: the broker is back when it has taken a
message, not merely answered the CONNECT.

Whatever a broker sends, memory and time stay bounded: every byte read goes through
:class:`~.mqtt_guard.InboundGuard` (no packet over 64 KiB, nothing a publishing client
never asks for, no acknowledgement of nothing), a broker that breaks the protocol is
dropped with one line, and the next attempt waits longer each time until a connection
has proved good (:mod:`.paho_hooks`).
"""

from __future__ import annotations

import os
import secrets
import ssl
import threading
import time
from collections.abc import Callable, Iterable
from typing import Any, Protocol

from ..commands.plant import Credentials, MqttAddress
from ..protocol import InputError
from ..protocol.text import endpoint, terminal_safe
from .extras import need
from .mqtt_guard import MOST_PACKET, InboundGuard
from .paho_hooks import Backoff, guarded_client

#: Messages handed to paho and not yet acknowledged, at most (the rest wait, coalesced).
IN_FLIGHT = 200
QOS = 1
#: Seconds between tries while the broker is away: from the first to the last, doubling.
RETRY_FIRST, RETRY_MOST = 1, 30
#: Keepalives a connection must have worked for before the broker counts as good again
#: (the backoff starts over, a breach of the protocol is said again).
GOOD_FOR = 2
#: Seconds a TCP connection and a TLS handshake may take.
CONNECT_TIMEOUT = 5.0
ONLINE, OFFLINE = b"online", b"offline"
#: Seconds between two messages of one topic, at least (the latest reading goes).
EVERY = 0.1
#: What :attr:`MqttFeed.state` can be; the trouble among them, said in one line each.
TROUBLE = ("away", "silent", "refused", "broken", "tls", "stopped")
STATES = ("connected", "connecting", *TROUBLE)


class Reading(Protocol):
    """A value as read, made into its payload only when it is sent."""

    def encode(self) -> bytes: ...


#: What a topic holds: a payload, or a reading to be made into one.
Held = bytes | Reading


class MqttFeed:
    """Start it, :meth:`update` from the engine's thread, :meth:`stop` it."""

    def __init__(
        self,
        address: MqttAddress,
        credentials: Credentials,
        target: str,
        say: Callable[[str], None],
        changed: Callable[[], None] = lambda: None,
    ) -> None:
        """``say`` tells the user something, ``changed`` that :attr:`state` changed
        (both from paho's thread or the feed's)."""
        mqtt = need("paho.mqtt.client", "publishing to MQTT")
        self._changed = changed
        self._dead = False
        self.address, self.target = address, target
        self.base = f"{address.prefix}/{target}"
        self._where = endpoint(address.host, address.port)
        self.status_topic = f"{self.base}/status"
        self._say = say
        self._lock = threading.Condition()
        self._latest: dict[str, Held] = {}  # every topic's last reading
        self._pending: dict[str, Held] = {}  # to be handed to paho
        self._sent_at: dict[str, float] = {}  # when each topic last went (monotonic)
        self._handed: dict[str, int] = {}  # each topic's last message id
        self._in_flight = 0  # handed to paho, not yet acknowledged (over reconnections)
        self._unacked: dict[int, tuple[str, Held]] = {}  # message id: topic, reading
        self._early: dict[int, Any] = {}  # acknowledged before its id was noted
        self._denied: set[str] = set()  # topics the broker refused (said once each)
        self._connected = False
        self._proved = False  # this connection's broker has taken a message
        self._republished = 0  # values published again at the last connection
        self._connected_at = 0.0  # when the last CONNACK came (monotonic)
        self._broken_said = False  # a breach of the protocol said in this spell
        self._back_said = False  # the broker said back in this spell of breaches
        self._trouble: str | None = None  # the kind of trouble said last: away, refused…
        self._stopping = False
        self.sent = 0  # messages acknowledged by the broker
        self._handed_total = 0  # messages handed to paho, ever: each is acknowledged once
        self._not_kept = mqtt.MQTT_ERR_QUEUE_SIZE  # the one refusal paho keeps nothing of
        self._keepalive = credentials.keepalive
        self._guard = InboundGuard(lambda: self._handed_total, self._keepalive)
        self._backoff = Backoff(RETRY_FIRST, RETRY_MOST)
        client = guarded_client(
            mqtt, f"rac-console-{secrets.token_hex(6)}", self._guard, self._backoff, self._crashed
        )
        client.connect_timeout = CONNECT_TIMEOUT
        client.will_set(self.status_topic, OFFLINE, qos=QOS, retain=True)
        if credentials.username is not None:
            client.username_pw_set(credentials.username, credentials.password)
        if address.tls:
            try:
                ca_file = credentials.ca_file
                client.tls_set(ca_certs=os.path.expanduser(ca_file) if ca_file else None)
            except (OSError, ValueError) as exc:
                where = credentials.ca_file or "the system's certificates"
                raise InputError(f"mqtts: cannot use {terminal_safe(where)}: {exc}") from None
        client.on_connect = self._on_connect
        client.on_connect_fail = self._on_connect_fail
        client.on_disconnect = self._on_disconnect
        client.on_publish = self._on_publish
        self._client = client
        self._feeder = threading.Thread(target=self._feed, name="rac-mqtt", daemon=True)

    def __str__(self) -> str:
        return f"{self.address}/{self.target}/…"

    # ------------------------------------------------------------ any thread

    def start(self) -> None:
        """Connect in the background: nothing here waits on the network."""
        from paho.mqtt.packettypes import PacketTypes
        from paho.mqtt.properties import Properties

        announced = Properties(PacketTypes.CONNECT)  # type: ignore[no-untyped-call]
        announced.MaximumPacketSize = MOST_PACKET  # what the guard enforces
        client = self._client
        client.connect_async(
            self.address.host, self.address.port, self._keepalive, properties=announced
        )
        client.loop_start()
        self._feeder.start()

    def _crashed(self, exc: Exception) -> None:
        """paho's network thread ended on what it does not catch itself: publishing
        stops with one line, never a traceback on the user's terminal."""
        with self._lock:
            self._connected, self._stopping, self._dead = False, True, True
            self._lock.notify_all()
        self._changed()
        self._say(
            f"publishing {self.target}'s values to {self} stopped: "
            f"{terminal_safe(str(exc)) or type(exc).__name__}"
        )

    def update(self, variable: str, payload: Held) -> None:
        """The latest of ``PREFIX/<target>/<variable>`` (never blocks on the network)."""
        self.update_many(((variable, payload),))

    def update_many(self, readings: Iterable[tuple[str, Held]]) -> None:
        """The latest of several variables at once (the engine's thread, at a flush:
        one lock for them all)."""
        base = self.base
        with self._lock:
            latest, pending = self._latest, self._pending
            for variable, reading in readings:
                topic = f"{base}/{variable}"
                latest[topic] = pending[topic] = reading
            self._lock.notify()

    def retire(self, variable: str, payload: bytes) -> None:
        """A variable no longer watched: its topic gets ``payload`` (no value, and why)
        once, and is not published again when the broker comes back."""
        topic = f"{self.base}/{variable}"
        with self._lock:
            self._latest.pop(topic, None)
            self._pending[topic] = payload
            self._lock.notify()

    @property
    def connected(self) -> bool:
        return self._connected

    @property
    def state(self) -> str:
        """One of :data:`STATES`: ``connected``; ``connecting`` (not yet, nothing wrong
        said); the trouble said (``away``, ``silent``: no MQTT there, ``refused``,
        ``broken``: it broke the protocol, ``tls``: no handshake or a certificate that does
        not verify); or ``stopped`` (it cannot go on)."""
        if self._dead:
            return "stopped"
        if self._connected:
            return "connected"
        return self._trouble or "connecting"

    def stop(self, timeout: float = 1.0, connecting: float = CONNECT_TIMEOUT) -> None:
        """Hand over what is pending (for up to ``timeout``), say ``offline`` on the
        status topic, and disconnect: a clean end sends no last will.

        A feed still on its first connection, with nothing said against the broker, is
        given up to ``connecting`` seconds to make it: a ``watch --count 1`` ends
        before a broker has answered, and its reading would be lost without a word."""
        with self._lock:
            if not self._connected and self._trouble is None and not self._dead:
                self._lock.wait_for(
                    lambda: self._connected or self._trouble is not None or self._dead,
                    connecting,
                )
            if self._connected:
                self._lock.wait_for(lambda: not self._pending and not self._in_flight, timeout)
            self._stopping = True
            connected = self._connected
            self._lock.notify_all()
        if connected:
            with self._lock:
                self._in_flight += 1
            self._publish(self.status_topic, OFFLINE)
            with self._lock:
                self._lock.wait_for(lambda: not self._in_flight, timeout)
        self._backoff.stop()
        self._client.disconnect()
        self._client.loop_stop()
        if self._feeder.is_alive():
            self._feeder.join(timeout)

    # ------------------------------------------------------------ the feed's thread

    def _feed(self) -> None:
        while True:
            with self._lock:
                due = self._due()
                while not due:
                    if self._stopping:
                        return
                    self._lock.wait(self._rest())
                    due = self._due()
                if self._stopping:
                    return
                now = time.monotonic()
                batch = [(topic, self._pending.pop(topic)) for topic in due]
                for topic in due:
                    self._sent_at[topic] = now
                self._in_flight += len(batch)
            # paho calls on_publish holding its own lock: never publish holding ours
            for topic, reading in batch:
                self._publish(topic, reading)

    def _due(self) -> list[str]:
        """The topics to send now (holding the lock): pending, their pace kept, within
        the room left in flight."""
        if self._stopping or not self._connected or not self._pending:
            return []
        room = IN_FLIGHT - self._in_flight
        if room <= 0:
            return []
        ready_before = time.monotonic() - EVERY
        sent_at = self._sent_at
        due = [t for t in self._pending if sent_at.get(t, 0.0) <= ready_before]
        return due[:room]

    def _rest(self) -> float | None:
        """How long the feed may sleep (holding the lock): until a pending topic's pace
        ends; None (until woken) when nothing is pending or nothing can go."""
        if self._stopping or not self._connected or not self._pending:
            return None
        if self._in_flight >= IN_FLIGHT:
            return None  # an acknowledgement wakes it
        sent_at = self._sent_at
        first = min(sent_at.get(t, 0.0) for t in self._pending) + EVERY
        return max(0.001, first - time.monotonic())

    def _publish(self, topic: str, reading: Held) -> None:
        """Hand one message to paho (counted in flight by the caller). Without a
        connection now paho keeps it and sends it on the next: it stays in flight."""
        data = reading if isinstance(reading, bytes) else reading.encode()
        with self._lock:  # counted before it can be acknowledged (see InboundGuard)
            self._handed_total += 1
        info = self._client.publish(topic, data, qos=QOS, retain=True)
        with self._lock:
            if info.rc == self._not_kept:  # refused: it goes with the next change or connection
                self._in_flight = max(0, self._in_flight - 1)
                self._lock.notify_all()
                return
            self._handed[topic] = info.mid
            reason = self._early.pop(info.mid, None)
            if reason is None:
                self._unacked[info.mid] = (topic, reading)
            else:
                self._catch_up(topic, reading)
        if reason is not None:
            self._acknowledged(topic, reason)

    def _catch_up(self, topic: str, reading: Held) -> None:
        """The broker took ``reading`` on ``topic`` (holding the lock): when that is not
        the latest, and the latest is neither waiting nor on its way, it was sent again by
        paho after the latest, and the latest goes once more."""
        latest = self._latest.get(topic)
        if latest is None or latest is reading or latest == reading or topic in self._pending:
            return
        on_its_way = self._unacked.get(self._handed.get(topic, -1))
        if on_its_way is not None and on_its_way[1] is latest:
            return  # handed after ``reading`` (the broker acknowledges in order)
        self._pending[topic] = latest
        self._lock.notify_all()

    # ------------------------------------------------------------ paho's thread

    def _on_connect(
        self, client: Any, userdata: Any, flags: Any, reason: Any, properties: Any
    ) -> None:
        if reason.is_failure:
            self._trouble_once(
                "refused",
                f"the MQTT broker {self._where} refused {self.target}'s connection "
                f"({reason}); trying again every {RETRY_MOST} s at most",
            )
            return
        with self._lock:
            if self._stopping:  # offline is said, or about to be: never online after it
                return
            self._connected, self._proved = True, False
            self._connected_at = time.monotonic()
            self._in_flight += 1  # the status; paho sends again what it had in flight
            self._pending = dict(self._latest)  # the broker may have lost them all
            self._sent_at.clear()
            self._republished = len(self._pending)
            self._lock.notify_all()
        self._publish(self.status_topic, ONLINE)
        self._changed()

    def _proves_good(self) -> None:
        """The broker took a message on this connection: it is back, said when its
        absence was (once in a spell of a broker breaking the protocol: see
        :meth:`_lasted`)."""
        self._proved = True
        if self._trouble is not None:  # the start was said by whoever started the feed
            quiet = self._trouble == "broken" and self._back_said
            self._back_said = self._back_said or self._trouble == "broken"
            self._trouble = None
            count = self._republished
            self._changed()
            if quiet:
                return
            self._say(
                f"the MQTT broker is back: {self.target}'s {count} value"
                f"{'s' * (count != 1)} published again"
            )

    def _on_connect_fail(self, client: Any, userdata: Any) -> None:
        failure: OSError | None = client.rac_failure
        again = f"trying again every {RETRY_MOST} s at most, polling goes on"
        if isinstance(failure, ssl.SSLCertVerificationError):
            self._trouble_once(
                "tls",
                f"the MQTT broker {self._where}'s certificate does not verify "
                f"({terminal_safe(failure.verify_message or str(failure))}): give the CA that "
                f"signed it as ca_file in the config's [mqtt] table or in RAC_MQTT_CA_FILE; "
                f"{again}",
            )
        elif client.rac_at_tls:
            why = terminal_safe(getattr(failure, "reason", None) or str(failure))
            self._trouble_once(
                "tls",
                f"no TLS handshake with the MQTT broker {self._where} ({why}): is it an "
                f"mqtts port? (mqtt:// for plain MQTT); {again}",
            )
        elif isinstance(failure, TimeoutError):
            self._trouble_once(
                "away",
                f"no answer from the MQTT broker {self._where} within {CONNECT_TIMEOUT:g} s "
                f"(a wrong address, or a firewall dropping the packets?); {again}",
            )
        else:
            why = "" if failure is None else f" ({terminal_safe(_reason(failure))})"
            self._trouble_once(
                "away",
                f"cannot reach the MQTT broker {self._where} for {self.target}{why}; {again}",
            )

    def _on_disconnect(
        self, client: Any, userdata: Any, flags: Any, reason: Any, properties: Any
    ) -> None:
        with self._lock:
            was = self._connected
            self._connected = False
            stopping = self._stopping
            self._lock.notify_all()
        if stopping:
            return
        self._lasted(was)
        broke, again = self._guard.broke, f"trying again every {RETRY_MOST} s at most"
        if broke is not None and not broke.first and self._broken_said:
            with self._lock:  # the same spell: shown on the status line, not said again
                self._trouble = "broken"
                self._lock.notify_all()
            self._changed()
        elif broke is not None and not broke.first:
            self._broken_said = True
            self._trouble_once(
                "broken",
                f"the MQTT broker {self._where} broke the protocol ({broke.why}): dropped it; "
                f"{again} (sooner at first), polling goes on",
            )
        elif was and reason == _KEEPALIVE_TIMEOUT:
            self._trouble_once(
                "away",
                f"the MQTT broker {self._where} stopped answering (no reply to a ping in "
                f"{self._keepalive:g} s); retrying, polling goes on: the latest of each of "
                f"{self.target}'s values goes out when it is back",
            )
        elif was:
            self._trouble_once(
                "away",
                f"lost the MQTT broker {self._where}; retrying, polling goes on: the latest "
                f"of each of {self.target}'s values goes out when it is back",
            )
        elif broke is not None or self._trouble is None:  # closed before a CONNACK
            what = f"{broke.why}: " if broke is not None else ""
            self._trouble_once(
                "silent",
                f"no MQTT answer from {self._where} ({what}is it an MQTT port? mqtts:// for "
                f"TLS); {again}, polling goes on",
            )

    def _lasted(self, was: bool) -> None:
        """A connection ended: when it had worked (a message taken) for
        :data:`GOOD_FOR` keepalives, the broker has proved good, and the next attempt
        waits the shortest time; a spell of breaking the protocol is over (its next
        breach is said again). A broker that answers and then breaks the protocol at
        once is retried ever more slowly, and said once."""
        good_for = GOOD_FOR * self._keepalive
        if was and self._proved and time.monotonic() - self._connected_at >= good_for:
            self._backoff.good()
            self._broken_said = self._back_said = False

    def _on_publish(
        self, client: Any, userdata: Any, mid: int, reason: Any, properties: Any
    ) -> None:
        with self._lock:
            self._in_flight = max(0, self._in_flight - 1)
            self.sent += 1
            sent = self._unacked.pop(mid, None)
            if sent is None:
                self._early[mid] = reason
            else:
                self._catch_up(*sent)
            self._lock.notify_all()
        if not self._proved and not reason.is_failure:  # a refusal proves nothing
            self._proves_good()
        if sent is not None:
            self._acknowledged(sent[0], reason)

    def _acknowledged(self, topic: str, reason: Any) -> None:
        if reason.is_failure and topic not in self._denied:
            self._denied.add(topic)
            self._say(f"the MQTT broker did not take {terminal_safe(topic)}: {reason}")

    def _trouble_once(self, kind: str, text: str) -> None:
        """Say ``text`` unless this kind of trouble was said already: a broker away
        (lost, then not reachable at each retry) is one line; a refusal after it, one more."""
        if self._trouble != kind:
            with self._lock:  # a stop waiting for the first connection ends its wait
                self._trouble = kind
                self._lock.notify_all()
            self._changed()
            self._say(text)


#: paho's reason when no answer came to a ping (MQTT 5's "Keep alive timeout").
_KEEPALIVE_TIMEOUT = 0x8D


def _reason(failure: OSError) -> str:
    """``Connection refused``, ``Name or service not known``: the OS's words for a
    failed connect (the sockets are paho's: this module touches none)."""
    return failure.strerror or str(failure) or type(failure).__name__
