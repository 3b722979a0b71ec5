"""``/metrics`` for Prometheus: the watched values' numbers, and how polling goes.

The engines write what they know to a :class:`MetricsBoard` (their own threads, a dict
under a lock); Prometheus's scrape reads it (the server's thread). prometheus-client
serves the text format, or OpenMetrics when the scraper asks for it.

    rac_value{target, variable, field, label}    a watched number (one per field of P, J, T, V)
    rac_read_ok{target, variable}                1 when the variable's last read succeeded
    rac_reads_total{target, result}              reads: ok, error (the controller said no), no_reply
    rac_poll_cycle_seconds{target}               the last poll cycle's length
    rac_rtt_seconds{target}                      the last round trip
    rac_connected{target}                        1 while the session is up

A value whose last read failed has no ``rac_value``: a stale number is not passed on as
the present one (``rac_read_ok`` says it failed).
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from ..commands.plant import MetricsAddress
from ..protocol import InputError
from .extras import need

READ_RESULTS = ("ok", "error", "no_reply")


@dataclass(frozen=True)
class TargetFigures:
    """How one target's polling goes, as its last status said."""

    connected: bool
    rtt: float | None
    cycle_seconds: float | None
    reads: tuple[int, int, int]  # ok, error, no_reply


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
            read_ok.add_metric((target, variable), 0.0 if fields is None else 1.0)
            for field, number in fields or ():
                value.add_metric((target, variable, field, label), number)
        reads = CounterMetricFamily(
            "rac_reads", "Reads of watched variables, by result", labels=("target", "result")
        )
        cycle = GaugeMetricFamily(
            "rac_poll_cycle_seconds", "The last poll cycle's length", labels=("target",)
        )
        rtt = GaugeMetricFamily("rac_rtt_seconds", "The last round trip", labels=("target",))
        connected = GaugeMetricFamily(
            "rac_connected", "1 while the session to the controller is up", labels=("target",)
        )
        for target, figure in sorted(figures.items()):
            for result, count in zip(READ_RESULTS, figure.reads, strict=True):
                reads.add_metric((target, result), count)
            if figure.cycle_seconds is not None:
                cycle.add_metric((target,), figure.cycle_seconds)
            if figure.rtt is not None:
                rtt.add_metric((target,), figure.rtt)
            connected.add_metric((target,), 1.0 if figure.connected else 0.0)
        yield from (value, read_ok, reads, cycle, rtt, connected)


class MetricsServer:
    """Serves a board's ``/metrics`` on a thread of its own until :meth:`stop`."""

    def __init__(self, address: MetricsAddress, board: MetricsBoard) -> None:
        """InputError when the extra is missing or the address cannot be served."""
        client = need("prometheus_client", "--metrics")
        registry = client.CollectorRegistry(auto_describe=False)
        registry.register(board)
        try:
            self._server, self._thread = client.start_http_server(
                address.port, address.host, registry
            )
        except OSError as exc:
            why = exc.strerror or str(exc)
            raise InputError(f"--metrics cannot serve {address}: {why}") from None
        self.address = address
        self.port = self._server.server_port

    def stop(self) -> None:
        self._server.shutdown()
        self._server.server_close()
