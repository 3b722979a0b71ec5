"""Whether a value read back is the value written, as the controller stores it.

A single float comes back as float32 holds it (1.1 reads back 1.100000023841858),
an IO bit as -1 or True: both are the value written. Pure.
"""

from __future__ import annotations

import math
from decimal import Decimal
from typing import Any

from ..protocol import Variant, VarKind
from ..protocol.variant import canonical_r4

#: A double read back within this relative difference is the value written (a
#: controller that prints 15 significant digits rounds the last one).
DOUBLE_TOLERANCE = 1e-12


def comparable(kind: VarKind, written: Variant) -> bool:
    """Whether a value written can be compared with the variable's own type: a raw PUT
    may write a string to an I (the controller converts it), which is no mismatch."""
    value = written.value
    if kind.labels:
        return isinstance(value, list)
    if kind.code == "S":
        return isinstance(value, str)
    if kind.code in ("I", "IO"):
        return isinstance(value, bool | int)
    return isinstance(value, bool | int | float | Decimal) and not isinstance(value, bool)


def same_value(kind: VarKind, written: Variant, read: Variant) -> bool:
    """True when ``read`` (a GET's answer) holds what ``written`` (a PUT's value) wrote."""
    if kind.code == "IO":
        return _truth(written.value) == _truth(read.value)
    if isinstance(written.value, list) or isinstance(read.value, list):
        if not (isinstance(written.value, list) and isinstance(read.value, list)):
            return False
        if len(written.value) != len(read.value):
            return False
        return all(
            _same_number(a, b, single=True) for a, b in zip(written.value, read.value, strict=True)
        )
    if kind.code == "S":
        return bool(written.value == read.value)
    if kind.code == "I":
        return _same_number(written.value, read.value, single=False, exact=True)
    return _same_number(written.value, read.value, single=kind.code == "F")


def _truth(value: Any) -> bool | None:
    if isinstance(value, bool | int):
        return bool(value)
    if isinstance(value, str) and value.lower() in ("true", "false"):
        return value.lower() == "true"
    return None


def _same_number(a: Any, b: Any, *, single: bool, exact: bool = False) -> bool:
    if isinstance(a, bool) or isinstance(b, bool):
        return bool(a == b)
    if not isinstance(a, int | float | Decimal) or not isinstance(b, int | float | Decimal):
        return False
    if exact or (isinstance(a, int) and isinstance(b, int)):
        return bool(a == b)
    x, y = float(a), float(b)
    if math.isnan(x) or math.isnan(y):
        return math.isnan(x) and math.isnan(y)
    if single:
        try:
            return canonical_r4(x) == canonical_r4(y)
        except OverflowError:  # beyond float32: the controller cannot hold it either
            return x == y
    return math.isclose(x, y, rel_tol=DOUBLE_TOLERANCE)
