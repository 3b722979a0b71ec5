"""A watched value as the plant receives it: a JSON payload for MQTT, numbers for
Prometheus. Pure: a value in, text or numbers out.

The value is the one ``--json`` prints, with the fields of a position, joint set,
transform or vector by name (``{"X": 350.0, ...}``): a dashboard reads ``value.X``
rather than counting. A string from the controller goes into the payload through JSON's
own escaping (``ensure_ascii``): whatever it holds, it stays one JSON string.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from datetime import UTC, datetime
from decimal import Decimal
from typing import Any

from ..commands.language import VarRef
from ..protocol import Variant
from ..protocol.vartypes import vt_name

OK = "OK"


def value_json(var: VarRef, variant: Variant) -> Any:
    """The value as ``--json`` gives it, a labelled kind's fields by name."""
    value = variant.to_json()
    labels = var.kind.labels
    if labels and isinstance(value, list) and len(value) == len(labels):
        return dict(zip(labels, value, strict=True))
    return value


def iso_time(wall: float) -> str:
    """``2026-11-26T10:15:02.123Z``: the time of the read, UTC, to the millisecond."""
    moment = datetime.fromtimestamp(wall, UTC)
    return moment.strftime("%Y-%m-%dT%H:%M:%S.") + f"{moment.microsecond // 1000:03d}Z"


def payload(
    target: str, var: VarRef, label: str, variant: Variant | None, status: str, wall: float
) -> bytes:
    """The retained message of ``PREFIX/<target>/<variable>``: the value (null unless
    the last read succeeded: a stale value is not passed on as the present one), its
    VARTYPE, the read's status and time, and where it comes from."""
    good = status == OK and variant is not None
    data: dict[str, Any] = {
        "value": value_json(var, variant) if good and variant is not None else None,
        "vartype": vt_name(variant.vt) if good and variant is not None else None,
        "status": status,
        "time": iso_time(wall),
        "target": target,
        "variable": str(var),
    }
    if label:
        data["label"] = label
    return json.dumps(data, ensure_ascii=True, allow_nan=False, default=str).encode("ascii")


@dataclass(frozen=True, slots=True, eq=False)
class Reading:
    """A watched value as read: its payload is made only if it is sent (a value that
    changes at every poll is sent at most every so often, its latest reading)."""

    target: str
    var: VarRef
    label: str
    variant: Variant | None
    status: str
    wall: float

    def encode(self) -> bytes:
        return payload(self.target, self.var, self.label, self.variant, self.status, self.wall)


def numeric_fields(var: VarRef, variant: Variant) -> list[tuple[str, float]]:
    """The numbers a value holds, by field (``""`` for a scalar; X, Y… for a labelled
    kind; 0, 1… for another array). Strings and NaN have none: Prometheus takes numbers."""
    value = variant.value
    if isinstance(value, bool | int | float):
        number = float(value)
        return [] if math.isnan(number) else [("", number)]
    if isinstance(value, list):
        labels = var.kind.labels if len(var.kind.labels) == len(value) else ()
        fields = []
        for n, item in enumerate(value):
            if isinstance(item, bool | int | float) and not math.isnan(float(item)):
                fields.append((labels[n] if labels else str(n), float(item)))
        return fields
    if isinstance(value, Decimal):  # VT_CY
        return [("", float(value))]
    return []
