"""RAC requests and responses (spec sections 2 and 6)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING

from .errors import InputError, ProtocolError
from .hresult import S_OK, hresult_name
from .variant import Variant, parse_hresult_number, parse_variant

if TYPE_CHECKING:
    from .variables import VarKind

MAX_FRAME = 256
"""Longest frame in bytes, CR included (spec 2)."""

PART_NAME = "RC8"


def get_request(kind: VarKind, index: int) -> str:
    return f"GET:{PART_NAME}:{index}:{kind.code}:"


def put_request(kind: VarKind, index: int, value_text: str) -> str:
    return f"PUT:{PART_NAME}:{index}:{kind.code}:{value_text}"


def is_well_formed_get(text: str) -> bool:
    """True only for ``GET:RC8:<index>:<type>:`` exactly: what read-only lets out.

    A whitelist, not a blacklist: leading bytes, a parameter, an unknown type or
    anything else that is not a plain read keeps the request off the wire.
    """
    from .variables import MAX_INDEX

    match = _get_pattern().fullmatch(text)
    return match is not None and int(match.group(1)) <= MAX_INDEX


@cache
def _get_pattern() -> re.Pattern[str]:
    """``GET:RC8:<index>:<type>:`` for the variable types the protocol has (made on first
    use: ``variables`` imports this module's neighbours)."""
    from .variables import KINDS

    codes = "|".join(sorted(KINDS, key=len, reverse=True))
    return re.compile(rf"GET:{PART_NAME}:(\d{{1,5}}):({codes}):", re.ASCII | re.IGNORECASE)


def encode_request(text: str) -> bytes:
    """The wire bytes of a request (text + CR); InputError if it cannot be sent."""
    if "\r" in text or "\n" in text:
        raise InputError("a request cannot contain CR or LF: CR ends a RAC frame")
    if not text.isascii():
        bad = next(ch for ch in text if not ch.isascii())
        raise InputError(f"RAC text is ASCII: {bad!r} cannot be sent")
    data = text.encode("ascii") + b"\r"
    if len(data) > MAX_FRAME:
        raise InputError(
            f"the request is {len(data)} bytes with its CR; RAC allows at most {MAX_FRAME}"
        )
    return data


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
