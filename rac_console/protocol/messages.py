"""RAC replies (spec sections 2 and 6): a reply line read into a :class:`Response`.

Requests are built and read in :mod:`.request`."""

from __future__ import annotations

from dataclasses import dataclass

from .errors import ProtocolError
from .hresult import S_OK, hresult_name
from .variant import Variant, parse_hresult_number, parse_variant


@dataclass(frozen=True, slots=True)
class Response:
    """A decoded reply line: result code and, for a GET, the value."""

    code: int
    variant: Variant | None

    @property
    def ok(self) -> bool:
        return self.code == S_OK

    @property
    def name(self) -> str | None:
        return hresult_name(self.code)


def parse_response(text: str) -> Response:
    """``<result>[,<data>]``; raise :class:`ProtocolError` on anything else."""
    head, sep, data = text.partition(",")
    code = parse_hresult_number(head.strip(" \t"))
    return Response(code, parse_variant(data) if sep else None)


def decode_frame(frame: bytes) -> str:
    """Frame bytes to text; RAC is ASCII, so any other byte is a protocol error."""
    try:
        return frame.decode("ascii")
    except UnicodeDecodeError as exc:
        raise ProtocolError(f"byte 0x{frame[exc.start]:02x} is not ASCII") from None
