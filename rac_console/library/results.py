"""What the library hands back: Python values, and the results of a write, a raw line and
a watch's read."""

from __future__ import annotations

from dataclasses import dataclass

#: A variable's value as Python holds it: I ``int``, F and D ``float``, S ``str``, IO
#: ``bool``, V, P, J and T a ``tuple`` of 3, 7, 8 and 10 floats.
Value = int | float | str | bool | tuple[float, ...]


@dataclass(frozen=True)
class Written:
    """A write as the console makes it: the value before (None: not read), the value
    written, the value the GET after the PUT answered (None: not read back), and whether
    it is the value written (None: not checked)."""

    variable: str  # I10, as the console writes it
    value: Value
    before: Value | None
    read_back: Value | None
    verified: bool | None


@dataclass(frozen=True)
class Sent:
    """A raw line's answer: its value (typed as :meth:`~rac_console.Connection.get` types
    it when the line names a variable; None when it carries none), the HRESULT, and the
    reply line as received, without its CR."""

    value: Value | None
    result: int
    raw: str


@dataclass(frozen=True)
class Reading:
    """One variable read by a watch: its name (``I10``), its value (None when the read
    failed), when its answer came (``time.time()``) and, when it failed, why."""

    name: str
    value: Value | None
    time: float
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None
