"""Pure RAC protocol code: no sockets, no asyncio, no UI imports.

Each name is imported from its module when first used (see :mod:`rac_console.lazy`):
``protocol.errors`` or ``protocol.text`` alone load nothing else of the package.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from .errors import EncodeError, FrameTooLong, InputError, ProtocolError, RacError
    from .framing import LineDecoder
    from .hresult import HRESULTS, describe_hresult, hresult_name
    from .messages import Response, decode_frame, parse_response
    from .request import (
        MAX_FRAME,
        Request,
        RequestLine,
        encode_request,
        get_request,
        parse_request,
        put_request,
    )
    from .text import escape_bytes, value_text, wire_text
    from .variables import KINDS, VarKind, encode_value, kind_of, parse_index
    from .variant import Variant, format_variant, parse_variant
    from .vartypes import VT, VT_ARRAY, vt_name

_WHERE = {
    **dict.fromkeys(
        ("EncodeError", "FrameTooLong", "InputError", "ProtocolError", "RacError"), ".errors"
    ),
    "LineDecoder": ".framing",
    **dict.fromkeys(("HRESULTS", "describe_hresult", "hresult_name"), ".hresult"),
    **dict.fromkeys(("Response", "decode_frame", "parse_response"), ".messages"),
    **dict.fromkeys(
        (
            "MAX_FRAME",
            "Request",
            "RequestLine",
            "encode_request",
            "get_request",
            "parse_request",
            "put_request",
        ),
        ".request",
    ),
    **dict.fromkeys(("escape_bytes", "value_text", "wire_text"), ".text"),
    **dict.fromkeys(("KINDS", "VarKind", "encode_value", "kind_of", "parse_index"), ".variables"),
    **dict.fromkeys(("Variant", "format_variant", "parse_variant"), ".variant"),
    **dict.fromkeys(("VT", "VT_ARRAY", "vt_name"), ".vartypes"),
}
__getattr__ = exports(__name__, _WHERE)

__all__ = [
    "HRESULTS",
    "KINDS",
    "MAX_FRAME",
    "VT",
    "VT_ARRAY",
    "EncodeError",
    "FrameTooLong",
    "InputError",
    "LineDecoder",
    "ProtocolError",
    "RacError",
    "Request",
    "RequestLine",
    "Response",
    "VarKind",
    "Variant",
    "decode_frame",
    "describe_hresult",
    "encode_request",
    "encode_value",
    "escape_bytes",
    "format_variant",
    "get_request",
    "hresult_name",
    "kind_of",
    "parse_index",
    "parse_request",
    "parse_response",
    "parse_variant",
    "put_request",
    "value_text",
    "vt_name",
    "wire_text",
]
