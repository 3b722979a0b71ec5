"""What came of one command: the shared result every front end renders.

Pure data: the JSON object of ``--json`` and the exit status are decided here
once, for the CLI, ``run``, the REPL and the console alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Any

from ..protocol import Response, Variant, describe_hresult, hresult_name
from ..protocol.text import counted
from .language import VarRef


class ExitStatus(IntEnum):
    OK = 0
    CONTROLLER_ERROR = 1  # the controller answered an error HRESULT
    REFUSED = 2  # refused before anything was sent
    TRANSPORT = 3  # no connection, timeout, or a reply that cannot be parsed
    LOCAL_IO = 4  # a local file failed (--record on a full disk); the work itself went on


@dataclass(frozen=True)
class Waited:
    """How a ``wait`` went: shown after the last value read, and in ``--json``."""

    condition: str  # IO128 on
    met: bool
    seconds: float  # from the first read sent to the reply that met it (or the last)
    reads: int
    within: float
    met_at: float | None = None  # time.time() of the reply that met it

    def text(self) -> str:
        reads = counted(self.reads, "read")
        if self.met:
            return f"{self.condition} after {self.seconds:.3f} s ({reads})"
        return f"{self.condition}: not met within {self.within:g} s ({reads})"

    def to_json(self) -> dict[str, Any]:
        return {
            "condition": self.condition,
            "met": self.met,
            "seconds": round(self.seconds, 3),
            "reads": self.reads,
            "within": self.within,
        }


@dataclass(frozen=True)
class Outcome:
    """The result of one exchange, or why there was none."""

    request: str | None
    status: ExitStatus
    var: VarRef | None = None
    response_text: str | None = None
    response: Response | None = None
    rtt: float | None = None
    error: str | None = None
    input_line: str | None = None
    written: Variant | None = None
    failure: Exception | None = None  # why no trustworthy reply came (not in the JSON)
    waited: Waited | None = None  # a wait: its condition, whether it was met, how long
    # A PUT read back (see engine/exchange/writes.py): the value before (None: not known), the
    # value the GET after it answered, whether that is the value written (None: not
    # checked: --no-verify, or the read-back failed), and why the read-back failed.
    before: Variant | None = None
    read_back: Variant | None = None
    verified: bool | None = None
    read_back_error: str | None = None
    #: The request may write (any line but a well-formed GET), it went out, and no
    #: trustworthy answer came (a timeout, the connection cut, a reply that cannot be
    #: read): it may have been applied, or may still arrive, and is never sent again.
    #: Set once, where the exchange failed (engine/exchange/execute.py), and its error
    #: says so; every front end reads it here (the library's ``OutcomeUnknown``).
    write_unknown: bool = False

    @property
    def ok(self) -> bool:
        return self.status == ExitStatus.OK

    @property
    def variant(self) -> Variant | None:
        return self.response.variant if self.response else None

    @property
    def rtt_ms(self) -> float | None:
        return None if self.rtt is None else round(self.rtt * 1000, 3)

    def summary(self) -> str:
        """One line for people: the HRESULT, or the error."""
        if self.error:
            return self.error
        assert self.response is not None
        return describe_hresult(self.response.code)

    def to_json(self) -> dict[str, Any]:
        variant = self.variant
        data: dict[str, Any] = {
            "request": self.request,
            "response": self.response_text,
            "ok": self.ok,
            "result": self.response.code if self.response else None,
            "result_name": hresult_name(self.response.code) if self.response else None,
            "vt": variant.vt if variant else None,
            "value": variant.to_json() if variant else None,
            "rtt_ms": self.rtt_ms,
        }
        if self.var is not None:
            data["variable"] = str(self.var)
        if self.input_line is not None:
            data["input"] = self.input_line
        if self.error:
            data["error"] = self.error
        if self.waited is not None:
            data["wait"] = self.waited.to_json()
        if self.written is not None or self.read_back is not None or self.read_back_error:
            data["before"] = self.before.to_json() if self.before is not None else None
            data["read_back"] = self.read_back.to_json() if self.read_back is not None else None
            data["verified"] = self.verified
            if self.read_back_error:
                data["read_back_error"] = self.read_back_error
        return data


def refused(line: str | None, message: str, request: str | None = None) -> Outcome:
    return Outcome(request, ExitStatus.REFUSED, error=message, input_line=line)


def worst(statuses: list[ExitStatus]) -> ExitStatus:
    """The exit status of a run: the most severe one seen."""
    return max(statuses, default=ExitStatus.OK)
