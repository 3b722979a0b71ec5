"""Plain-text renderings of values and wire bytes, shared by every front end.

:func:`terminal_safe` is used everywhere, the console's first paint included: the value
types and their names load with the first value shown.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from decimal import Decimal
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .messages import Response
    from .variant import Variant

CR_MARK = "↵"


def endpoint(host: str, port: int) -> str:
    """``10.0.0.5:5006``, ``[fe80::1]:5006``."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def counted(n: int, noun: str) -> str:
    """``1 row``, ``3 rows``: a count and its noun, for messages."""
    return f"{n} {noun}{'s' * (n != 1)}"


def close_match(word: str, choices: Iterable[str]) -> str | None:
    """The choice closest to a mistyped ``word`` (case aside), as the choice is written;
    None when none is close: a guess that far off would mislead more than help."""
    by_folded = {choice.casefold(): choice for choice in choices}
    found = difflib.get_close_matches(word.casefold(), by_folded, n=1)
    return by_folded[found[0]] if found else None


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


def terminal_safe(text: str) -> str:
    """The one escaping function for text that came from the wire or a file.

    Every character a terminal could act on (C0 controls such as ESC, BEL, BS and
    LF, DEL, the C1 range such as the CSI byte 0x9B, and Unicode format characters
    such as bidirectional overrides) is written as ``\\xNN`` or ``\\uNNNN``, so
    it is shown, never obeyed and never silently dropped.
    """
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() else _escape_char(ch) for ch in text)


def quoted_text(text: str) -> str:
    """A string value in a result: in double quotes, so an empty string and leading or
    trailing spaces show (``""``, ``" x "``); ``"`` and ``\\`` inside escaped with a
    backslash, as JSON writes them, and every control character as :func:`terminal_safe`."""
    inner = text.replace("\\", "\\\\").replace('"', '\\"')
    return f'"{terminal_safe(inner)}"'


def terminal_safe_lines(text: str) -> str:
    """:func:`terminal_safe` line by line: our own multi-line text keeps its lines."""
    return "\n".join(terminal_safe(line) for line in text.split("\n"))


def _escape_char(ch: str) -> str:
    code = ord(ch)
    if code < 0x100:
        return f"\\x{code:02x}"
    if code < 0x10000:
        return f"\\u{code:04x}"
    return f"\\U{code:08x}"


def wire_text(data: bytes) -> str:
    """A frame as shown in logs: escaped, with its CR made visible."""
    if data.endswith(b"\r"):
        return escape_bytes(data[:-1]) + CR_MARK
    return escape_bytes(data)


def scalar_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        from .variant import float_text

        return float_text(value)
    if isinstance(value, Decimal):
        return format(value.normalize(), "f")
    if value is None:
        return "(empty)"
    if isinstance(value, str):
        return terminal_safe(value)
    if isinstance(value, int):
        return str(value)
    from .variant import Variant  # a value inside a value: rare

    if isinstance(value, Variant):
        from .vartypes import vt_name

        return f"({vt_name(value.vt)} {value_text(value)})"
    return str(value)


def value_text(variant: Variant) -> str:
    """A compact one-line rendering of any decoded value."""
    if isinstance(variant.value, list):
        return ", ".join(scalar_text(v) for v in variant.value)
    return scalar_text(variant.value)


def describe_response(response: Response) -> str:
    """A reply decoded in one line: ``S_OK  VT_I4  123`` or the HRESULT explained."""
    from .hresult import describe_hresult
    from .vartypes import vt_name

    if not response.ok:
        return describe_hresult(response.code)
    if response.variant is None:
        return "S_OK"
    variant = response.variant
    return f"S_OK  {vt_name(variant.vt)}  {value_text(variant)}"
