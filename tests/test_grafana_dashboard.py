"""The Grafana dashboard shipped in ``deploy/grafana/`` asks only for what the exporter
serves: every metric and label its queries name is read from a real scrape of
``/metrics`` (a board filled as an engine fills it), not from a list kept by hand."""

from __future__ import annotations

import json
import re
import urllib.request
from pathlib import Path

import pytest

from rac_console.commands.plant import parse_metrics_address
from rac_console.plant.metrics import MetricsBoard, TargetFigures

pytest.importorskip("prometheus_client")
from prometheus_client.parser import text_string_to_metric_families

from rac_console.plant.metrics_server import MetricsServer

DASHBOARD = Path(__file__).resolve().parent.parent / "deploy/grafana/dashboards/rac-console.json"
METRIC = re.compile(r"\b(rac_[a-z_]+)\b")
SELECTOR = re.compile(r"\{([^}]*)\}")
LABEL = re.compile(r"\b([a-z_]+)\s*(?:=~|!~|!=|=)")
BY = re.compile(r"\bby\s*\(([^)]*)\)")


def queries() -> list[str]:
    dashboard = json.loads(DASHBOARD.read_text(encoding="utf-8"))
    found = [t["expr"] for panel in dashboard["panels"] for t in panel.get("targets", [])]
    for variable in dashboard["templating"]["list"]:
        if variable["type"] == "query":
            found.append(variable["definition"])
    return found


def served() -> tuple[set[str], set[str]]:
    """The sample names and label names of a scrape of a board holding what an engine
    writes: a number, a failed read, a target's figures."""
    board = MetricsBoard()
    board.set_value("robotA", "P1", "pick", [("X", 350.0), ("Y", 0.0)])
    board.set_value("robotA", "IO128", "gripper", [("", 1.0)])
    board.set_value("robotA", "I2", "", None)
    board.set_figures("robotA", TargetFigures(True, 0.002, 0.1, (10, 1, 0), 0.1))
    server = MetricsServer(parse_metrics_address("127.0.0.1:0"), board)
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{server.port}/metrics", timeout=10) as page:
            text = page.read().decode("utf-8")
    finally:
        server.stop()
    names, labels = set[str](), set[str]()
    for family in text_string_to_metric_families(text):
        for sample in family.samples:
            names.add(sample.name)
            labels.update(sample.labels)
    return names, labels


def test_every_metric_and_label_the_dashboard_asks_for_is_served() -> None:
    names, labels = served()
    asked = queries()
    assert len(asked) >= 8
    for query in asked:
        for metric in METRIC.findall(query):
            assert metric in names, f"{metric} (in {query!r}) is not served: {sorted(names)}"
        for selector in SELECTOR.findall(query):
            for label in LABEL.findall(selector):
                assert label in labels, f"label {label} (in {query!r}) is not served"
        for grouped in BY.findall(query):
            for label in (word.strip() for word in grouped.split(",")):
                assert label in labels, f"label {label} (in {query!r}) is not served"


def test_the_dashboard_covers_what_the_plant_asks_to_see() -> None:
    """Per target: connection state, round trip, poll cycle against the interval, read
    errors, the watched values, and I/O as state timelines."""
    dashboard = json.loads(DASHBOARD.read_text(encoding="utf-8"))
    by_title = {panel["title"]: panel for panel in dashboard["panels"]}
    wanted = {
        "Connection": ("state-timeline", "rac_connected"),
        "Round trip": ("timeseries", "rac_rtt_seconds"),
        "Poll cycle against the interval": ("timeseries", "rac_poll_interval_seconds"),
        "Read errors": ("timeseries", "rac_reads_total"),
        "Watched values": ("timeseries", "rac_value"),
        "I/O": ("state-timeline", 'variable=~"IO.*"'),
    }
    for title, (kind, asks) in wanted.items():
        panel = by_title[title]
        assert panel["type"] == kind
        assert any(asks in target["expr"] for target in panel["targets"]), title
        assert all('target=~"$target"' in target["expr"] for target in panel["targets"]), title
