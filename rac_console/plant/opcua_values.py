"""A watched value as OPC UA serves it, and a client's write as a ``put`` would type it.

Each RAC kind has one OPC UA type (I Int32, F Float, D Double, S String, IO Boolean;
V, P, J and T arrays of Float), so a SCADA tag's type never changes under it. A value
is Good only when its last read succeeded and is not stale; otherwise it is Bad, with
no value: the controller gone (BadCommunicationError) or an error it answered
(BadDeviceFailure; the variable's ``Status`` says which).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from asyncua import ua

from ..commands.language import VarRef
from ..protocol import InputError, Variant
from ..protocol.variables import VarKind

OK = "OK"
#: The statuses of a read that got no answer from the controller (the others are the
#: RAC errors it answered).
NO_ANSWER = frozenset({"TIMEOUT", "DISCONNECTED", "BAD REPLY", "SKIPPED", "WAITING"})

_SCALARS: dict[str, ua.VariantType] = {
    "I": ua.VariantType.Int32,
    "F": ua.VariantType.Float,
    "D": ua.VariantType.Double,
    "S": ua.VariantType.String,
    "IO": ua.VariantType.Boolean,
}


def variant_type(kind: VarKind) -> ua.VariantType:
    """The OPC UA type of a kind's values (of their items, for an array)."""
    return _SCALARS.get(kind.code, ua.VariantType.Float)


def is_array(kind: VarKind) -> bool:
    return kind.code not in _SCALARS


def initial_value(kind: VarKind) -> ua.Variant:
    """The value a variable is made with, before its first read (served Bad)."""
    vtype = variant_type(kind)
    if is_array(kind):
        return ua.Variant([0.0] * kind.count, vtype, is_array=True)
    empty: dict[ua.VariantType, Any] = {
        ua.VariantType.Int32: 0,
        ua.VariantType.Float: 0.0,
        ua.VariantType.Double: 0.0,
        ua.VariantType.String: "",
        ua.VariantType.Boolean: False,
    }
    return ua.Variant(empty[vtype], vtype)


@dataclass(frozen=True, slots=True)
class Served:
    """One watched value as the plant last saw it (made on the engine's thread)."""

    var: VarRef
    label: str
    variant: Variant | None
    status: str
    stale: bool
    wall: float  # when it was read (time.time())


def data_value(served: Served, paused: bool = False) -> ua.DataValue:
    """The DataValue a client reads: the value and Good, or Bad and no value; while its
    target's polling is paused, a good value is UncertainLastUsableValue: not read
    since."""
    source = datetime.fromtimestamp(served.wall, UTC)
    now = datetime.now(UTC)
    good = served.status == OK and not served.stale and served.variant is not None
    if good and served.variant is not None:
        try:
            value = opcua_variant(served.var.kind, served.variant)
        except (TypeError, ValueError, OverflowError):
            return bad(ua.StatusCodes.BadTypeMismatch, source, now)
        code = ua.StatusCodes.UncertainLastUsableValue if paused else ua.StatusCodes.Good
        return ua.DataValue(value, ua.StatusCode(code), source, now)
    if served.status in NO_ANSWER or served.status == OK:  # OK and stale: no answer since
        return bad(ua.StatusCodes.BadCommunicationError, source, now)
    return bad(ua.StatusCodes.BadDeviceFailure, source, now)


def bad(code: int, source: datetime, now: datetime) -> ua.DataValue:
    return ua.DataValue(ua.Variant(None, ua.VariantType.Null), ua.StatusCode(code), source, now)


def opcua_variant(kind: VarKind, variant: Variant) -> ua.Variant:
    """The value in its kind's OPC UA type; ValueError when the controller's value does
    not fit it (a VT the kind does not have)."""
    value = variant.value
    vtype = variant_type(kind)
    if is_array(kind):
        if not isinstance(value, list):
            raise ValueError("not an array")
        return ua.Variant([float(item) for item in value], vtype, is_array=True)
    if vtype is ua.VariantType.Int32:
        if isinstance(value, bool) or not isinstance(value, int) or not -(2**31) <= value < 2**31:
            raise ValueError("not an Int32")
        return ua.Variant(value, vtype)
    if vtype is ua.VariantType.String:
        if not isinstance(value, str):
            raise ValueError("not a string")
        return ua.Variant(value, vtype)
    if vtype is ua.VariantType.Boolean:
        if not isinstance(value, bool | int):
            raise ValueError("not a Boolean")
        return ua.Variant(bool(value), vtype)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError("not a number")
    return ua.Variant(float(value), vtype)


def put_text(kind: VarKind, value: Any) -> str:
    """A client's value as ``put`` takes it typed, so that it is checked as a typed one
    is (range, CR in a string, the fields of a position); InputError when it cannot be
    written at all."""
    if kind.code == "S":
        if not isinstance(value, str):
            raise InputError("S takes a String")
        quote = "'" if '"' in value else '"'
        return f"{quote}{value}{quote}"
    if kind.code == "IO":
        if not isinstance(value, bool):
            raise InputError("IO takes a Boolean")
        return "on" if value else "off"
    if is_array(kind):
        if not isinstance(value, list) or len(value) != kind.count:
            raise InputError(f"{kind.code} takes {kind.count} Floats: {kind.value_hint}")
        return " ".join(_number(item, kind.code) for item in value)
    if kind.code == "I":
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError("I takes an Int32")
        return str(value)
    return _number(value, kind.code)


def _number(value: Any, code: str) -> str:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{code} takes numbers")
    if not math.isfinite(float(value)):
        raise InputError(f"{code} takes finite numbers, not {value!r}")
    return repr(float(value))
