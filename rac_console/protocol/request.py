"""A request ready for the wire: its text, its bytes and the check its reply must pass.

Built once, where a command is parsed (or once per variable, for polls), and carried
to the session as it is: nothing downstream builds the text again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING

from .messages import Response, encode_request, get_request, is_well_formed_get, put_request

if TYPE_CHECKING:
    from .variables import VarKind

ReplyCheck = Callable[[Response], "str | None"]


@dataclass(frozen=True, slots=True)
class Request:
    """``text`` as typed or built, ``data`` its wire bytes (CR included).

    ``check`` says why a reply cannot answer it (None: any well-formed reply can);
    ``write`` marks a PUT, whose outcome a timeout leaves unknown.
    """

    text: str
    data: bytes
    check: ReplyCheck | None = None
    write: bool = False

    @property
    def read_only_safe(self) -> bool:
        """True only for ``GET:RC8:<index>:<type>:`` exactly: what read-only lets out."""
        return is_well_formed_get(self.text)


def raw_request(text: str) -> Request:
    """A line sent exactly as typed; InputError when it cannot be a frame."""
    return Request(text, encode_request(text), write=text.lstrip(" \t")[:3].upper() == "PUT")


@cache
def get_for(kind: VarKind, index: int) -> Request:
    """The GET of one variable, made once: the poller asks for it thousands of times."""
    text = get_request(kind, index)
    return Request(text, encode_request(text), _get_check(kind))


def put_for(kind: VarKind, index: int, value_text: str) -> Request:
    """The PUT of ``value_text`` (already RAC text); InputError when it cannot be sent."""
    text = put_request(kind, index, value_text)
    return Request(text, encode_request(text), _put_check, write=True)


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


def _put_check(response: Response) -> str | None:
    if response.variant is not None:
        return "a PUT reply carries no value"
    return None
