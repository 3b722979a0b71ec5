"""Requests (spec sections 2 and 6): building them, and reading a request line once.

A :class:`Request` is a request ready for the wire: its text, its bytes, what those
bytes say (:class:`RequestLine`) and the check its reply must pass. It is built once,
where a command is parsed (or once per variable, for polls), and carried to the
session as it is: nothing downstream builds the text again or reads it again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

from .errors import InputError
from .messages import Response
from .variables import KINDS, MAX_INDEX, VarKind

MAX_FRAME = 256
"""Longest frame in bytes, CR included (spec 2)."""

PART_NAME = "RC8"

#: Digits of an index in a well-formed request line (``GET:RC8:00010:I:`` is I10).
MAX_INDEX_DIGITS = 5

ReplyCheck = Callable[[Response], "str | None"]


@dataclass(frozen=True, slots=True)
class RequestLine:
    """What one request line says, read once by :func:`parse_request`.

    ``command`` is the line's first word (the text before its first ``:``, blanks
    around it dropped, upper-cased): ``GET``, ``PUT`` or whatever was sent. ``var``
    (type and index) names the variable when the line starts with a well-formed
    ``GET:RC8:<index>:<type>:`` or ``PUT:RC8:<index>:<type>:`` (any case, no blank
    before it); ``value`` is then the text after that head (a PUT's value), else None.
    """

    command: str
    var: tuple[VarKind, int] | None = None
    value: str | None = None

    @property
    def is_get(self) -> bool:
        """True only for ``GET:RC8:<index>:<type>:`` exactly: what read-only lets out.

        A whitelist, not a blacklist: leading bytes, a parameter, an unknown type or
        anything else that is not a plain read keeps the request off the wire.
        """
        return self.command == "GET" and self.var is not None and self.value == ""

    @property
    def is_put(self) -> bool:
        """True for ``PUT:RC8:<index>:<type>:<value>``: a write of a variable we can name."""
        return self.command == "PUT" and self.var is not None

    @property
    def writes(self) -> bool:
        """True when the line starts with PUT (blanks aside), well formed or not: a
        controller may take it as a write, whose outcome a timeout leaves unknown."""
        return self.command.startswith("PUT")

    def names(self, code: str, index: int) -> bool:
        """True when the line gets or puts the variable ``code`` ``index`` (``IO``, 128)."""
        return self.var is not None and self.var[0].code == code and self.var[1] == index


def parse_request(line: str | bytes) -> RequestLine:
    """Read a request line once: its command word, its variable and its value.

    ``bytes`` are a frame as sent, its CR (the frame's end) not part of the line; any
    byte that is not ASCII only keeps the line from being well formed.
    """
    text = line.removesuffix(b"\r").decode("latin-1") if isinstance(line, bytes) else line
    command, _, rest = text.partition(":")
    word = command.strip(" \t").upper()
    fields = rest.split(":", 3)
    if len(fields) != 4 or not command.isascii() or command.upper() not in ("GET", "PUT"):
        return RequestLine(word)
    part, number, code, value = fields
    if not (
        part.isascii()
        and part.upper() == PART_NAME
        and number.isascii()
        and number.isdigit()
        and len(number) <= MAX_INDEX_DIGITS
        and code.isascii()
    ):
        return RequestLine(word)
    kind = KINDS.get(code.upper())
    index = int(number)
    if kind is None or index > MAX_INDEX:
        return RequestLine(word)
    return RequestLine(word, (kind, index), value)


@dataclass(frozen=True, slots=True)
class Request:
    """``text`` as typed or built, ``data`` its wire bytes (CR included), ``line``
    what those bytes say (read once, here).

    ``check`` says why a reply cannot answer it (None: any well-formed reply can).
    """

    text: str
    data: bytes
    line: RequestLine
    check: ReplyCheck | None = None

    @property
    def write(self) -> bool:
        """A PUT (or any line starting with PUT), whose outcome a timeout leaves unknown."""
        return self.line.writes

    @property
    def read_only_safe(self) -> bool:
        """True only for ``GET:RC8:<index>:<type>:`` exactly: what read-only lets out."""
        return self.line.is_get


def get_request(kind: VarKind, index: int) -> str:
    return f"GET:{PART_NAME}:{index}:{kind.code}:"


def put_request(kind: VarKind, index: int, value_text: str) -> str:
    return f"PUT:{PART_NAME}:{index}:{kind.code}:{value_text}"


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


def _request(text: str, check: ReplyCheck | None = None) -> Request:
    """A request for ``text``, its bytes read once; InputError when it cannot be a frame."""
    data = encode_request(text)
    return Request(text, data, parse_request(data), check)


def raw_request(text: str) -> Request:
    """A line sent exactly as typed; InputError when it cannot be a frame."""
    return _request(text)


@cache
def get_for(kind: VarKind, index: int) -> Request:
    """The GET of one variable, made once: the poller asks for it thousands of times."""
    return _request(get_request(kind, index), _get_check(kind))


def put_for(kind: VarKind, index: int, value_text: str) -> Request:
    """The PUT of ``value_text`` (already RAC text); InputError when it cannot be sent."""
    return _request(put_request(kind, index, value_text), _put_check)


@cache
def _get_check(kind: VarKind) -> ReplyCheck:
    """One check per variable type, made once (it is on every poll's path)."""

    def check(response: Response) -> str | None:
        if not response.ok:
            return None
        if response.variant is None:
            return "S_OK with no value"
        return kind.reply_problem(response.variant)

    return check


def get_check(kind: VarKind) -> ReplyCheck:
    """The reply check of a GET of ``kind`` (the same object each time)."""
    return _get_check(kind)


def put_for_check() -> ReplyCheck:
    """The reply check of a PUT."""
    return _put_check


def _put_check(response: Response) -> str | None:
    if response.variant is not None:
        return "a PUT reply carries no value"
    return None
