"""What a broker may send the feed, checked byte by byte as it arrives.

The feed only publishes: it never subscribes, so all an honest MQTT 5 broker sends it is
one CONNACK first, a PUBACK for each message it took, a PINGRESP for each ping and maybe
a DISCONNECT, each a few bytes. paho-mqtt reads any packet whole, however long its fixed
header says it is (256 MB from a hostile broker: hundreds of MB of memory and seconds of
the interpreter), and takes any number of acknowledgements for nothing. This guard sees
every byte before paho does: a packet longer than :data:`MOST_PACKET` (the maximum
packet size the feed announces in its CONNECT), a type the feed never asked for, a
first answer that is not a CONNACK, or more acknowledgements than messages sent ends the
connection at once, saying why in one line. So does a packet that takes longer than a
keepalive to arrive (a drip of a byte a second keeps paho's own keepalive content).

Pure: bytes in, :class:`BrokerMisbehaved` out.
"""

from __future__ import annotations

import time
from collections.abc import Callable

#: Bytes of one packet from the broker, at most, announced in the CONNECT (MQTT 5's
#: Maximum Packet Size) and enforced here: a CONNACK with every property it can carry
#: is far smaller.
MOST_PACKET = 65_536
#: Bytes asked of the socket at once, at most (paho asks for a whole packet's length).
CHUNK = 16_384

CONNACK, PUBACK, PINGRESP, DISCONNECT = 2, 4, 13, 14
_NAMES = (
    "a packet of type 0 (reserved)", "a CONNECT", "a CONNACK", "a PUBLISH", "a PUBACK",
    "a PUBREC", "a PUBREL", "a PUBCOMP", "a SUBSCRIBE", "a SUBACK", "an UNSUBSCRIBE",
    "an UNSUBACK", "a PINGREQ", "a PINGRESP", "a DISCONNECT", "an AUTH",
)  # fmt: skip
_HEADER, _LENGTH, _BODY = range(3)


class BrokerMisbehaved(ConnectionError):
    """The broker sent what no MQTT 5 broker sends a publishing client: paho, which
    sees an OSError from its socket, drops the connection. ``first``: it was the
    connection's first answer (then it is likely no MQTT broker at all)."""

    def __init__(self, why: str, first: bool = False) -> None:
        super().__init__(why)
        self.why, self.first = why, first


class InboundGuard:
    """Follows the packets of one connection after another (:meth:`new_connection`)."""

    def __init__(
        self,
        sent: Callable[[], int],
        keepalive: float,
        most: int = MOST_PACKET,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        """``sent``: messages handed for sending so far, over every connection (each
        gets one acknowledgement at most); ``keepalive``: the seconds a packet may take."""
        self._sent, self._keepalive, self._most, self._clock = sent, keepalive, most, clock
        self._acks = 0  # whole acknowledgements, over every connection, as ``sent`` counts
        self.new_connection()

    def pinged(self) -> None:
        """A PINGREQ went out on this connection: one PINGRESP may come for it."""
        self._pings_sent += 1

    def new_connection(self) -> None:
        self.broke: BrokerMisbehaved | None = None  # why this connection was dropped
        self._state, self._packets, self._pings, self._pings_sent = _HEADER, 0, 0, 0
        self._kind = self._length = self._left = self._length_bytes = 0
        self._started = 0.0  # when the packet being read began to arrive

    def take(self, data: bytes) -> None:
        """Follow ``data``; BrokerMisbehaved at the first byte that cannot be honest."""
        try:
            self._follow(data)
        except BrokerMisbehaved as exc:
            self.broke = exc
            raise

    def _follow(self, data: bytes) -> None:
        at, end = 0, len(data)
        if self._state != _HEADER and self._clock() - self._started > self._keepalive:
            raise BrokerMisbehaved(
                f"it took over {self._keepalive:g} s to send one {_NAMES[self._kind][2:]}"
            )
        while at < end:
            if self._state == _HEADER:
                self._header(data[at])
                at += 1
            elif self._state == _LENGTH:
                self._length_byte(data[at])
                at += 1
            else:
                step = min(self._left, end - at)
                at += step
                self._left -= step
                if not self._left:
                    self._packet_done()

    def _packet_done(self) -> None:
        """A whole packet read: only now is an acknowledgement counted (a connection
        lost mid-packet leaves the message unacknowledged, and paho sends it again)."""
        self._state = _HEADER
        if self._kind == PUBACK:
            self._acks += 1
            if self._acks > self._sent():
                raise BrokerMisbehaved(
                    f"it acknowledged {self._acks:,} messages, {self._sent():,} were sent"
                )

    def _header(self, byte: int) -> None:
        kind, flags = byte >> 4, byte & 0x0F
        first = self._packets == 0
        self._packets += 1
        if first and kind != CONNACK:
            raise BrokerMisbehaved("its first answer is not an MQTT CONNACK", first=True)
        if kind not in (CONNACK, PUBACK, PINGRESP, DISCONNECT) or flags:
            raise BrokerMisbehaved(f"it sent {_NAMES[kind]}, which this client never asks for")
        if kind == CONNACK and not first:
            raise BrokerMisbehaved("it sent a second CONNACK")
        if kind == PINGRESP:
            self._pings += 1
            if self._pings > self._pings_sent:
                raise BrokerMisbehaved("it answers pings that were not sent")
        self._kind, self._state, self._started = kind, _LENGTH, self._clock()
        self._length = self._length_bytes = 0

    def _length_byte(self, byte: int) -> None:
        self._length += (byte & 0x7F) << (7 * self._length_bytes)
        self._length_bytes += 1
        if byte & 0x80:
            if self._length_bytes == 4:
                raise BrokerMisbehaved("it sent a packet length of more than 4 bytes")
            return
        if self._length > self._most:
            raise BrokerMisbehaved(
                f"it announced {_NAMES[self._kind]} of {self._length:,} bytes "
                f"({self._most:,} at most)"
            )
        self._left = self._length
        if self._length:
            self._state = _BODY
        else:
            self._packet_done()
