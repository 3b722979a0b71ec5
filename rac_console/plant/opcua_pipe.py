"""The messages between the feeding process and the OPC UA server's own (msgpack lists
over a pipe, one writer a side).

Feeder to server: ``["settings", host, port, security, writes, user, password]`` first
(the password never on a command line), then ``["rows", [[target, key, row], ...]]``
(``row`` a :data:`Row`, None: unwatched; under key ``""`` the whole target, ENDED or
FORGET), ``["answer", number, status, said]`` and ``["stop"]``.

Server to feeder: ``["ready", port, certificate, made]`` or ``["failed", text]``, then
``["say", text, target]`` and ``["write", number, target, code, index, text]``.
"""

from __future__ import annotations

import threading
from typing import Any, BinaryIO

import msgpack

#: One watched value: kind code, index, label, value (None: no value), status, stale,
#: time of the read.
Row = tuple[str, int, str, Any, str, bool, float]
#: A target's engine ended (its values go Bad, its folder stays), or its folder goes.
ENDED, FORGET = "ended", "forget"


class Pipe:
    """Messages in from ``reader``, out to ``writer`` (sends from any thread)."""

    def __init__(self, reader: BinaryIO, writer: BinaryIO) -> None:
        self._reader = reader
        self._writer = writer
        self._unpacker = msgpack.Unpacker(raw=False, strict_map_key=False)
        self._lock = threading.Lock()

    def send(self, message: list[Any]) -> None:
        data = msgpack.packb(message, use_bin_type=True)
        with self._lock:
            self._writer.write(data)
            self._writer.flush()

    def receive(self) -> list[Any] | None:
        """The next message; None once the other side has gone."""
        while True:
            for message in self._unpacker:
                return list(message)
            chunk = self._reader.read1(65536)  # type: ignore[attr-defined]
            if not chunk:
                return None
            self._unpacker.feed(chunk)


def plain(value: Any) -> Any:
    """A value msgpack carries as it is (the kinds served hold no other), else None."""
    if isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, list) and all(isinstance(item, bool | int | float) for item in value):
        return value
    return None
