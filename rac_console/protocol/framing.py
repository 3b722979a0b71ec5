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

    __slots__ = ("max_line", "pending")

    def __init__(self, max_line: int = 64 * 1024) -> None:
        self.max_line = max_line
        #: Bytes received after the last CR (read before every request: an attribute).
        self.pending = b""

    def feed(self, data: bytes) -> list[bytes]:
        buffer = self.pending + data if self.pending else data
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
        self.pending = b""

    def _hold(self, rest: bytes) -> None:
        if len(rest) > self.max_line:
            self.pending = b""
            raise FrameTooLong(f"no CR within {self.max_line} bytes")
        self.pending = rest
