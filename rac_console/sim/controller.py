"""The simulated RC8: its variable store and its answer to each request line.

Pure: time comes from an injected clock, so tests can drive the moving values.
A client polling the same variables sends the same lines again and again, so the reply
to a GET of a value that does not move by itself is kept, keyed by the line, until the
next PUT: parsing and formatting were most of the simulator's time per request.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

from ..protocol import KINDS, ProtocolError, Variant, VarKind, format_variant, parse_variant
from ..protocol.hresult import (
    E_ACCESSDENIED,
    E_INVALIDARG,
    E_INVALIDARGTYPE,
    E_INVALIDCOMMAND,
    E_INVALIDRCVPACKET,
    E_UNEXPECTED,
    S_OK,
)
from ..protocol.variant import canonical_r4
from ..protocol.vartypes import INTEGER_RANGES, NUMERIC_TYPES, VT, element_type, is_array

VARIABLE_COUNT = 100
IO_COUNT = 512
MAX_REQUEST = 256
MAX_CACHED = 1024  # replies kept; a client sending ever new lines only empties it again

#: Variables that change by themselves, so a live watch has something to show.
#: They are read-only, like a robot's current position and its input ports.
MOVING = {("I", 0), ("F", 0), ("P", 0), ("J", 0), *(("IO", n) for n in range(8))}


def _initial_store() -> dict[str, list[Any]]:
    store: dict[str, list[Any]] = {
        "I": [0] * VARIABLE_COUNT,
        "F": [0.0] * VARIABLE_COUNT,
        "D": [0.0] * VARIABLE_COUNT,
        "S": [""] * VARIABLE_COUNT,
        "V": [[0.0, 0.0, 0.0] for _ in range(VARIABLE_COUNT)],
        "P": [[0.0] * 6 + [-1.0] for _ in range(VARIABLE_COUNT)],
        "J": [[0.0] * 8 for _ in range(VARIABLE_COUNT)],
        "T": [[0.0] * 3 + [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, -1.0] for _ in range(VARIABLE_COUNT)],
        "IO": [False] * IO_COUNT,
    }
    store["I"][1:6] = [1, 250, 3, 12, 100]
    store["F"][1:4] = [0.5, 25.0, 9.80665]
    store["D"][1:3] = [3.141592653589793, 1500.25]
    store["S"][1:4] = ["RC8 simulator", "PRO_MAIN", "part OK"]
    store["V"][1] = [0.0, 0.0, 100.0]
    store["P"][1] = [350.0, 0.0, 450.0, 180.0, 0.0, 180.0, 5.0]
    store["P"][2] = [400.0, -120.5, 300.25, 180.0, 0.0, 90.0, 5.0]
    store["P"][3] = [280.0, 200.0, 150.0, -180.0, 0.0, 135.0, 1.0]
    store["J"][1] = [0.0, 30.0, 90.0, 0.0, 60.0, 0.0, 0.0, 0.0]
    store["J"][2] = [-45.0, 15.0, 110.0, 0.0, 55.0, 90.0, 0.0, 0.0]
    store["T"][1] = [350.0, 0.0, 450.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 5.0]
    for port in (128, 130, 131):
        store["IO"][port] = True
    return store


def _r4(values: list[float]) -> list[float]:
    return [canonical_r4(v) for v in values]


class SimulatedController:
    """Answers RAC request lines the way an RC8 does (spec section 6)."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self._start = clock()
        self._store = _initial_store()
        self.requests = 0
        self._replies: dict[bytes, bytes] = {}  # GET line: its reply, until the next PUT
        #: The same replies keyed by the line with its CR, as one read of a client that
        #: keeps one request in flight holds it: the server's fast path looks them up
        #: without splitting. Emptied in place, never replaced.
        self.known_frames: dict[bytes, bytes] = {}
        self._keep = False  # set by _answer: this line's reply may be kept

    # ---------------------------------------------------------------- values

    def value(self, kind: VarKind, index: int) -> Any:
        """The value a GET would answer now."""
        if (kind.code, index) in MOVING:
            return self._moving_value(kind.code, index, self._clock() - self._start)
        return self._store[kind.code][index]

    def variant(self, kind: VarKind, index: int) -> Variant:
        return Variant(kind.vt, self.value(kind, index))

    @staticmethod
    def _moving_value(code: str, index: int, t: float) -> Any:
        if code == "I":
            return int(t * 10) % 2_147_483_647  # a cycle counter at 10 Hz
        if code == "F":
            return canonical_r4(36.5 + 1.5 * math.sin(t / 7))  # a motor temperature
        if code == "IO":
            return int(t * (index + 1) / 2) % 2 == 1  # input bits blinking at their own rates
        phase = t / 4
        if code == "J":
            return _r4(
                [
                    30 * math.sin(phase),
                    20 + 10 * math.sin(phase / 2),
                    90 - 15 * math.cos(phase),
                    0.0,
                    60 + 5 * math.sin(phase),
                    45 * math.sin(phase / 3),
                    0.0,
                    0.0,
                ]
            )
        return _r4(
            [
                350 + 50 * math.cos(phase),
                80 * math.sin(phase),
                400 + 30 * math.sin(phase / 2),
                180.0,
                0.0,
                180 + 20 * math.sin(phase),
                5.0,
            ]
        )

    def count(self, kind: VarKind) -> int:
        return len(self._store[kind.code])

    # -------------------------------------------------------------- requests

    def handle(self, line: bytes) -> tuple[bytes, bool]:
        """The reply frame (CR included) to one request line, and whether to close."""
        self.requests += 1
        reply = self._replies.get(line)
        if reply is not None:
            return reply, False
        if len(line) + 1 > MAX_REQUEST:
            return code_reply(E_INVALIDRCVPACKET), True
        try:
            text = line.decode("ascii")
        except UnicodeDecodeError:
            return code_reply(E_INVALIDCOMMAND), False
        self._keep = False
        try:
            reply = self._answer(text.lstrip(" \t")).encode("ascii") + b"\r"
        except Exception:  # a bug here must cost one answer, never the session
            return code_reply(E_UNEXPECTED), False
        if self._keep and self._own_values():
            if len(self._replies) >= MAX_CACHED:
                self.forget()
            self._replies[line] = reply
            self.known_frames[line + b"\r"] = reply
        return reply, False

    def _own_values(self) -> bool:
        """False when a test replaced value() or variant() (its values may move): then
        no reply is kept."""
        cls, own = type(self), vars(self)
        return (
            "value" not in own
            and "variant" not in own
            and cls.value is SimulatedController.value
            and cls.variant is SimulatedController.variant
        )

    def set(self, code: str, index: int, value: Any) -> None:
        """Change a variable from outside RAC (a simulated cell's handshake), as a PUT
        would: the kept replies go."""
        self._store[code][index] = value
        self.forget()

    def forget(self) -> None:
        """Drop the kept replies: call it after changing the store other than by PUT."""
        self._replies.clear()
        self.known_frames.clear()

    def _answer(self, text: str) -> str:
        request = read_request(text)
        if request is None:
            return _code(E_INVALIDCOMMAND)
        command, kind, index, parameter = request
        if index >= self.count(kind):
            return _code(E_INVALIDARG)
        if command == "GET":
            if parameter.strip(" \t"):
                return _code(E_INVALIDCOMMAND)
            self._keep = (kind.code, index) not in MOVING  # same line, same reply until a PUT
            return "0," + format_variant(self.variant(kind, index))
        self.forget()
        return _code(self._put(kind, index, parameter))

    def _put(self, kind: VarKind, index: int, parameter: str) -> int:
        try:
            variant = parse_variant(parameter)
        except ProtocolError:
            return E_INVALIDARG
        if (kind.code, index) in MOVING:
            return E_ACCESSDENIED
        try:
            self._store[kind.code][index] = _convert(kind, variant)
        except TypeError:
            return E_INVALIDARGTYPE
        except ValueError:
            return E_INVALIDARG
        return S_OK


def read_request(text: str) -> tuple[str, VarKind, int, str] | None:
    """``(command, kind, index, parameter)`` of a request line as an RC8 reads it (case
    and indentation aside, ``GET:RC8:010:i:`` is ``GET:RC8:10:I:``); None when it is not
    a GET or PUT of a known type (E_INVALIDCOMMAND). One reading, so a replay keys its
    recorded requests exactly as the simulator answers them."""
    fields = text.lstrip(" \t").split(":", 4)
    if len(fields) != 5:
        return None
    command, part, number, subcommand, parameter = fields
    command = command.upper()
    kind = KINDS.get(subcommand.upper())
    if command not in ("GET", "PUT") or part.upper() != "RC8" or kind is None:
        return None
    if not number.isascii() or not number.isdigit():
        return None
    return command, kind, int(number), parameter


def _code(code: int) -> str:
    """Result codes are written as signed decimal, like a C ``%d`` of an HRESULT."""
    return str(code - 2**32 if code >= 2**31 else code)


def code_reply(code: int) -> bytes:
    """A reply that is a result code alone, with its CR: what a request that failed gets."""
    return _code(code).encode("ascii") + b"\r"


def _number(vt: int, value: Any) -> float:
    """A numeric VARIANT value as a float; TypeError for anything else."""
    if isinstance(value, Variant):
        return _number(value.vt, value.value)
    if vt not in NUMERIC_TYPES or is_array(vt):
        raise TypeError(vt)
    if isinstance(value, bool):
        return -1.0 if value else 0.0
    return float(value)


def _convert(kind: VarKind, variant: Variant) -> Any:
    """The stored value for a PUT, converting between numeric VARTYPEs.

    TypeError: the VARTYPE cannot become this type; ValueError: out of range or
    the wrong element count.
    """
    vt, value = variant.vt, variant.value
    if kind.labels:
        if not is_array(vt):
            raise TypeError(vt)
        base = element_type(vt)
        numbers = [_number(base, v) for v in value]
        if len(numbers) != kind.count:
            raise ValueError(f"{kind.code} takes {kind.count} values")
        try:
            return _r4(numbers)
        except OverflowError:
            raise ValueError("out of range") from None
    if kind.code == "S":
        if vt != VT.BSTR:
            raise TypeError(vt)
        if not value.isprintable():
            raise ValueError("control characters cannot be stored")
        return value
    number = _number(vt, value)
    if kind.code == "IO":
        return number != 0
    if kind.code == "I":
        integer = round(number)
        low, high = INTEGER_RANGES[VT.I4]
        if not low <= integer <= high:
            raise ValueError("out of range")
        return integer
    if kind.code == "F":
        try:
            return canonical_r4(number)
        except OverflowError:
            raise ValueError("out of range") from None
    return number
