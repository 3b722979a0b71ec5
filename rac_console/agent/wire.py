"""The agent's messages on a socket: each a msgpack map with an ``op`` (see
``docs/agent.md``), sent whole under a lock, read one at a time.

The first message each way is the hello: the protocol's number and the release, which
must both be this one's, else the client is refused in one line and goes direct.
"""

from __future__ import annotations

import contextlib
import hashlib
import hmac
import os
import secrets
import socket
import sys
import threading
from collections.abc import Iterator
from typing import Any

from ..release import __version__
from . import codec

#: Changes whenever a message changes; the release must match too (the events are the
#: engine's own dataclasses).
PROTOCOL = 1
#: A message larger than this is refused (a batch of 100,000 frames is about 8 MB).
MAX_MESSAGE = 64 * 1024 * 1024
RELEASE = __version__

Message = dict[str, Any]


class ChannelClosed(ConnectionError):
    """The other end went away (or sent what no message of this release is)."""


class Channel:
    """One end of a connection between the agent and a client (any thread sends)."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self._send_lock = threading.Lock()
        self._unpacker = codec.unpacker(MAX_MESSAGE)
        self.closed = False

    def send(self, message: Message) -> None:
        data = codec.pack(message)
        with self._send_lock:
            try:
                self.sock.sendall(data)
            except OSError as exc:
                self.closed = True
                raise ChannelClosed(str(exc)) from None

    def messages(self) -> Iterator[Message]:
        """The messages received, in order, until the other end closes."""
        while True:
            try:
                for message in self._unpacker:
                    if not isinstance(message, dict) or "op" not in message:
                        raise ChannelClosed("a message with no op")
                    yield message
            except codec.DecodeError as exc:
                raise ChannelClosed(str(exc)) from None
            except Exception as exc:  # msgpack's own: over MAX_MESSAGE, or malformed
                raise ChannelClosed(f"a message that cannot be read: {exc}") from None
            try:
                data = self.sock.recv(1 << 20)
            except OSError as exc:
                self.closed = True
                raise ChannelClosed(str(exc)) from None
            if not data:
                self.closed = True
                return
            self._unpacker.feed(data)

    def receive(self) -> Message:
        """The next message (ChannelClosed when none comes)."""
        for message in self.messages():
            return message
        raise ChannelClosed("the other end closed the connection")

    def set_timeout(self, seconds: float | None) -> None:
        """How long a receive waits (None: as long as the other end lives)."""
        self.sock.settimeout(seconds)

    def peer_is_us(self) -> bool:
        """Whether the other end of a Unix socket runs as this user (Linux: the
        kernel's credentials of the peer; elsewhere the folder's mode is the guard)."""
        if sys.platform == "win32" or not hasattr(socket, "SO_PEERCRED"):
            return True
        if self.sock.family != socket.AF_UNIX:
            return True
        import struct

        size = struct.calcsize("3i")
        creds = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, size)
        _pid, uid, _gid = struct.unpack("3i", creds)
        return bool(uid == os.getuid())

    def close(self) -> None:
        self.closed = True
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)
        self.sock.close()


def hello_problem(message: Message) -> str | None:
    """Why a hello cannot be taken (another protocol or release), or None."""
    if message.get("op") != "hello":
        return "the first message was no hello"
    release = message.get("release")
    if message.get("protocol") != PROTOCOL or release != RELEASE:
        return (
            f"the agent runs rac-console {RELEASE}, this is {release}: "
            "restart the agent with this release, or use --direct"
        )
    return None


def hello(token: str, **fields: object) -> Message:
    """A client's first message: this release, the agent's token (Windows), a nonce the
    agent proves it holds the token with (:func:`proven`), and ``fields``."""
    return {
        "op": "hello",
        "protocol": PROTOCOL,
        "release": RELEASE,
        "token": token,
        "nonce": secrets.token_hex(16),
        **fields,
    }


def proof(token: str, nonce: object) -> str:
    """What the agent answers a hello with: the client's nonce signed with the token."""
    return hmac.new(token.encode(), str(nonce).encode(), hashlib.sha256).hexdigest()


def proven(token: str, sent: Message, answer: Message) -> bool:
    """Whether ``answer`` came from the agent that wrote ``token``: on Windows, where a
    port left by an agent that died could be taken by any program, it must carry the
    proof; a Unix socket's peer is checked by the kernel (no token there)."""
    if not token:
        return True
    return hmac.compare_digest(str(answer.get("proof", "")), proof(token, sent.get("nonce")))


def greet(channel: Channel, token: str, **fields: object) -> Message | None:
    """A client's hello (:func:`hello`) and the agent's answer; None, the channel closed,
    when no answer comes or it is not the agent's (:func:`proven`)."""
    sent = hello(token, **fields)
    try:
        channel.send(sent)
        answer = channel.receive()
    except (ChannelClosed, OSError):
        channel.close()
        return None
    if not proven(token, sent, answer):  # not the agent: a port it left, taken
        channel.close()
        return None
    return answer
