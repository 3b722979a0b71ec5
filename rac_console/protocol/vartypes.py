"""VARTYPE numbers and names, as in the vendor's table (spec section 3)."""

from __future__ import annotations

from enum import IntEnum


class VT(IntEnum):
    EMPTY = 0
    NULL = 1
    I2 = 2
    I4 = 3
    R4 = 4
    R8 = 5
    CY = 6
    DATE = 7
    BSTR = 8
    ERROR = 10
    BOOL = 11
    VARIANT = 12
    UI1 = 17
    UI2 = 18
    UI4 = 19


VT_ARRAY = 0x2000

#: Element types an array may carry.
ARRAY_ELEMENT_TYPES = frozenset(
    {
        VT.I2,
        VT.I4,
        VT.R4,
        VT.R8,
        VT.CY,
        VT.DATE,
        VT.BSTR,
        VT.ERROR,
        VT.BOOL,
        VT.VARIANT,
        VT.UI1,
        VT.UI2,
        VT.UI4,
    }
)

INTEGER_RANGES: dict[VT, tuple[int, int]] = {
    VT.I2: (-(2**15), 2**15 - 1),
    VT.I4: (-(2**31), 2**31 - 1),
    VT.UI1: (0, 2**8 - 1),
    VT.UI2: (0, 2**16 - 1),
    VT.UI4: (0, 2**32 - 1),
}

NUMERIC_TYPES = frozenset({VT.I2, VT.I4, VT.R4, VT.R8, VT.CY, VT.UI1, VT.UI2, VT.UI4, VT.BOOL})


def is_array(vt: int) -> bool:
    return bool(vt & VT_ARRAY)


def element_type(vt: int) -> int:
    return vt & ~VT_ARRAY


def is_known(vt: int) -> bool:
    """True for every VARTYPE this codec reads and writes."""
    if is_array(vt):
        return element_type(vt) in ARRAY_ELEMENT_TYPES
    return vt in VT._value2member_map_


def vt_name(vt: int) -> str:
    """``VT_I4``, ``VT_R4|VT_ARRAY``, or ``VT 9`` for a number outside the table."""
    if is_array(vt):
        base = element_type(vt)
        if base in VT._value2member_map_:
            return f"VT_{VT(base).name}|VT_ARRAY"
        return f"VT {vt}"
    if vt in VT._value2member_map_:
        return f"VT_{VT(vt).name}"
    return f"VT {vt}"
