"""``/metrics`` for Prometheus: the watched values' numbers, and how polling goes.

The engines write what they know to a :class:`MetricsBoard` (their own threads, a dict
under a lock); Prometheus's scrape reads it (the server's thread). prometheus-client
serves the text format, or OpenMetrics when the scraper asks for it.

    rac_value{target, variable, field, label}    a watched number (one per field of P, J, T, V)
    rac_read_ok{target, variable}                1 when the variable's last read succeeded
    rac_reads_total{target, result}              reads: ok, error (the controller said no), no_reply
    rac_poll_cycle_seconds{target}               the last poll cycle's length
    rac_poll_interval_seconds{target}            the interval asked for (0: flat out)
    rac_rtt_seconds{target}                      the last round trip
    rac_connected{target}                        1 while the session is up

A value whose last read failed has no ``rac_value``: a stale number is not passed on as
the present one (``rac_read_ok`` says it failed).

Every label value is made terminal-safe here (ESC, BEL, C1 and format characters as
``\x1b``…): prometheus-client escapes only quotes, backslashes and newlines, and a page
read with ``curl`` in a terminal must not be obeyed by it. :mod:`.metrics_server` serves
the page.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from ..protocol.text import terminal_safe

READ_RESULTS = ("ok", "error", "no_reply")


@dataclass(frozen=True)
class TargetFigures:
    """How one target's polling goes, as its last status said."""

    connected: bool
    rtt: float | None
    cycle_seconds: float | None
    reads: tuple[int, int, int]  # ok, error, no_reply
    interval: float | None = None  # the poll interval asked for


class MetricsBoard:
    """What ``/metrics`` shows: written by the engines, read at each scrape."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        #: (target, variable): (label, fields or None when the last read failed)
        self._values: dict[tuple[str, str], tuple[str, list[tuple[str, float]] | None]] = {}
        self._figures: dict[str, TargetFigures] = {}

    def set_value(
        self, target: str, variable: str, label: str, fields: list[tuple[str, float]] | None
    ) -> None:
        with self._lock:
            self._values[target, variable] = (label, fields)

    def remove(self, target: str, variable: str) -> None:
        with self._lock:
            self._values.pop((target, variable), None)

    def forget(self, target: str) -> None:
        """A target no longer polled (another opened in its place): its series go."""
        with self._lock:
            self._values = {key: v for key, v in self._values.items() if key[0] != target}
            self._figures.pop(target, None)

    def set_figures(self, target: str, figures: TargetFigures) -> None:
        with self._lock:
            self._figures[target] = figures

    def collect(self) -> Iterator[Any]:
        """The metric families, for prometheus-client's registry."""
        from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily

        with self._lock:
            values = dict(self._values)
            figures = dict(self._figures)
        value = GaugeMetricFamily(
            "rac_value",
            "A watched variable's number (one per field of P, J, T, V)",
            labels=("target", "variable", "field", "label"),
        )
        read_ok = GaugeMetricFamily(
            "rac_read_ok",
            "1 when the variable's last read succeeded",
            labels=("target", "variable"),
        )
        for (target, variable), (label, fields) in sorted(values.items()):
            target, variable, label = _safe(target), _safe(variable), _safe(label)
            read_ok.add_metric((target, variable), 0.0 if fields is None else 1.0)
            for field, number in fields or ():
                value.add_metric((target, variable, _safe(field), label), number)
        reads = CounterMetricFamily(
            "rac_reads", "Reads of watched variables, by result", labels=("target", "result")
        )
        cycle = GaugeMetricFamily(
            "rac_poll_cycle_seconds", "The last poll cycle's length", labels=("target",)
        )
        interval = GaugeMetricFamily(
            "rac_poll_interval_seconds",
            "The poll interval asked for (0: as fast as the controller answers)",
            labels=("target",),
        )
        rtt = GaugeMetricFamily("rac_rtt_seconds", "The last round trip", labels=("target",))
        connected = GaugeMetricFamily(
            "rac_connected", "1 while the session to the controller is up", labels=("target",)
        )
        for name, figure in sorted(figures.items()):
            target = _safe(name)
            for result, count in zip(READ_RESULTS, figure.reads, strict=True):
                reads.add_metric((target, result), count)
            if figure.cycle_seconds is not None:
                cycle.add_metric((target,), figure.cycle_seconds)
            if figure.interval is not None:
                interval.add_metric((target,), figure.interval)
            if figure.rtt is not None:
                rtt.add_metric((target,), figure.rtt)
            connected.add_metric((target,), 1.0 if figure.connected else 0.0)
        yield from (value, read_ok, reads, cycle, interval, rtt, connected)


def _safe(text: str) -> str:
    """A label value no terminal acts on (see the module)."""
    return terminal_safe(text)
