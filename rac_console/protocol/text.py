"""Plain-text renderings of values and wire bytes, shared by every front end."""

from __future__ import annotations

from decimal import Decimal
from typing import Any

from .hresult import describe_hresult
from .messages import Response
from .variant import Variant, float_text
from .vartypes import vt_name

CR_MARK = "↵"


def escape_bytes(data: bytes) -> str:
    """Printable ASCII as is; every other byte as ``\\xNN`` (backslash doubled)."""
    out = []
    for byte in data:
        if byte == 0x5C:
            out.append("\\\\")
        elif 0x20 <= byte < 0x7F:
            out.append(chr(byte))
        else:
            out.append(f"\\x{byte:02x}")
    return "".join(out)


def printable(text: str) -> str:
    """Text safe to put on a terminal: control characters as ``\\xNN``."""
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() else f"\\x{ord(ch):02x}" for ch in text)


def wire_text(data: bytes) -> str:
    """A frame as shown in logs: escaped, with its CR made visible."""
    if data.endswith(b"\r"):
        return escape_bytes(data[:-1]) + CR_MARK
    return escape_bytes(data)


def scalar_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return float_text(value)
    if isinstance(value, Decimal):
        return format(value.normalize(), "f")
    if isinstance(value, Variant):
        return f"({vt_name(value.vt)} {value_text(value)})"
    if value is None:
        return "(empty)"
    if isinstance(value, str):
        return printable(value)
    return str(value)


def value_text(variant: Variant) -> str:
    """A compact one-line rendering of any decoded value."""
    if isinstance(variant.value, list):
        return ", ".join(scalar_text(v) for v in variant.value)
    return scalar_text(variant.value)


def describe_response(response: Response) -> str:
    """A reply decoded in one line: ``S_OK  VT_I4  123`` or the HRESULT explained."""
    if not response.ok:
        return describe_hresult(response.code)
    if response.variant is None:
        return "S_OK"
    variant = response.variant
    return f"S_OK  {vt_name(variant.vt)}  {value_text(variant)}"
