"""Incremental CR-terminated line decoder shared by the client and the simulator."""

from __future__ import annotations

from .errors import FrameTooLong

CR = b"\r"


class LineDecoder:
    """``feed(bytes) -> frames``: complete lines without their CR; the rest is kept.

    A line that grows past ``max_line`` bytes without a CR raises
    :class:`FrameTooLong` and the decoder drops what it held, so memory stays
    bounded whatever a peer sends. An LF right after a CR (a CRLF peer) is dropped
    from the start of the next line.
    """

    __slots__ = ("_buffer", "max_line")

    def __init__(self, max_line: int = 64 * 1024) -> None:
        self.max_line = max_line
        self._buffer = b""

    @property
    def pending(self) -> bytes:
        """Bytes received after the last CR."""
        return self._buffer

    def feed(self, data: bytes) -> list[bytes]:
        buffer = self._buffer + data if self._buffer else data
        if CR not in buffer:
            self._hold(buffer)
            return []
        *lines, rest = buffer.split(CR)
        lines = [line[1:] if line[:1] == b"\n" else line for line in lines]
        try:
            self._hold(rest)
        except FrameTooLong as exc:
            exc.lines = lines
            raise
        return lines

    def clear(self) -> None:
        self._buffer = b""

    def _hold(self, rest: bytes) -> None:
        if len(rest) > self.max_line:
            self._buffer = b""
            raise FrameTooLong(f"no CR within {self.max_line} bytes")
        self._buffer = rest
