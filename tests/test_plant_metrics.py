"""``--metrics``: the real CLI as a subprocess serving ``/metrics``, scraped with a plain
HTTP client and read back with Prometheus's own text parsers."""

from __future__ import annotations

import re
import time
import urllib.request
from collections.abc import Callable
from pathlib import Path

import pytest
from mqtt_broker import Running, running
from servers import CLOSE, RecordingServer
from test_cli import cli, env, one_error_line, recording

from rac_console.commands.plant import parse_metrics_address
from rac_console.engine import Engine
from rac_console.plant.metrics import MetricsBoard, MetricsServer

prometheus = pytest.importorskip("prometheus_client")
from prometheus_client.openmetrics.parser import (  # noqa: E402
    text_string_to_metric_families as openmetrics_families,
)
from prometheus_client.parser import text_string_to_metric_families  # noqa: E402

pytestmark = pytest.mark.slow
env = env  # the fixtures: a private HOME for the CLI, servers that stop with the test
recording = recording
running = running
SERVING = re.compile(r"serving the watched values at (http://127\.0\.0\.1:\d+/metrics)")

Samples = dict[tuple[str, tuple[tuple[str, str], ...]], float]


def scrape(url: str, openmetrics: bool = False) -> tuple[str, str]:
    """The page and its content type, as Prometheus asks for it."""
    accept = "application/openmetrics-text; version=1.0.0" if openmetrics else "text/plain"
    request = urllib.request.Request(url, headers={"Accept": accept})
    with urllib.request.urlopen(request, timeout=10) as response:
        return response.read().decode("utf-8"), response.headers["Content-Type"]


def samples(text: str, parse: Callable[[str], object] = text_string_to_metric_families) -> Samples:
    """Every sample by name and labels (sorted), read by Prometheus's parser."""
    found: Samples = {}
    for family in parse(text):  # type: ignore[attr-defined]
        for sample in family.samples:
            found[sample.name, tuple(sorted(sample.labels.items()))] = sample.value
    return found


def labels(**given: str) -> tuple[tuple[str, str], ...]:
    return tuple(sorted(given.items()))


def serving(watch: Running) -> str:
    watch.wait_for("the address served", lambda: any(SERVING.search(e) for e in watch.err))
    found = next(SERVING.search(e) for e in watch.err if SERVING.search(e))
    assert found is not None
    return found.group(1)


def test_the_watched_numbers_are_scraped_with_their_fields_and_counters(
    env: dict[str, str], running: list[Running]
) -> None:
    watch = Running(env, "watch", "I", "1", "P", "1", "S", "1", "--every", "0.1", "--metrics", "0")
    running.append(watch)
    url = serving(watch)
    watch.wait_for("two cycles", lambda: len(watch.out) >= 2)

    def read() -> Samples:
        return samples(scrape(url)[0])

    got = read()
    value = "rac_value"
    assert got[value, labels(target="sim", variable="I1", field="", label="")] == 1.0
    p1 = {field: got[value, labels(target="sim", variable="P1", field=field, label="")]
          for field in ("X", "Y", "Z", "Rx", "Ry", "Rz", "Fig")}  # fmt: skip
    assert p1 == {"X": 350.0, "Y": 0.0, "Z": 450.0, "Rx": 180.0, "Ry": 0.0, "Rz": 180.0, "Fig": 5.0}
    assert not any(key[0] == value and ("variable", "S1") in key[1] for key in got)  # text
    assert got["rac_read_ok", labels(target="sim", variable="S1")] == 1.0
    assert got["rac_connected", labels(target="sim")] == 1.0
    assert ("rac_poll_cycle_seconds", labels(target="sim")) in got
    assert ("rac_rtt_seconds", labels(target="sim")) in got
    ok = got["rac_reads_total", labels(target="sim", result="ok")]
    assert ok >= 3 and got["rac_reads_total", labels(target="sim", result="no_reply")] == 0
    # The counter counts on: a later scrape, after more cycles, has more.
    seen = len(watch.out)
    watch.wait_for("more cycles", lambda: len(watch.out) >= seen + 3)
    later = samples(scrape(url)[0])
    assert later["rac_reads_total", labels(target="sim", result="ok")] > ok

    text, kind = scrape(url, openmetrics=True)
    assert kind.startswith("application/openmetrics-text")
    assert text.rstrip().endswith("# EOF")
    assert (
        samples(text, openmetrics_families)[
            "rac_value", labels(target="sim", variable="I1", field="", label="")
        ]
        == 1.0
    )
    assert watch.stop() == 0


def test_a_failed_read_leaves_no_number_and_counts_as_a_failure(
    env: dict[str, str], recording: Callable[..., RecordingServer], running: list[Running]
) -> None:
    answers = {b"GET:RC8:1:I:": b"0,3,7\r", b"GET:RC8:2:I:": b"-2147024809\r"}
    server = recording(lambda line: answers.get(line, CLOSE))
    watch = Running(
        env, *server.args, "watch", "I", "1", "I", "2", "--every", "0.1", "--metrics", "0"
    )
    running.append(watch)
    url = serving(watch)
    target = f"127.0.0.1:{server.port}"
    watch.wait_for("two cycles", lambda: len(watch.out) >= 2)
    got = samples(scrape(url)[0])
    assert got["rac_value", labels(target=target, variable="I1", field="", label="")] == 7.0
    assert got["rac_read_ok", labels(target=target, variable="I1")] == 1.0
    assert got["rac_read_ok", labels(target=target, variable="I2")] == 0.0
    assert not any(k[0] == "rac_value" and ("variable", "I2") in k[1] for k in got)
    assert got["rac_reads_total", labels(target=target, result="error")] >= 1
    watch.stop()


def test_a_label_with_quotes_and_braces_is_escaped_by_the_exposition() -> None:
    board = MetricsBoard()
    server = MetricsServer(parse_metrics_address("127.0.0.1:0"), board)
    engine = Engine(None, interval=0.05, timeout=2.0, metrics=board)
    hostile = 'a} 1 rac_value{target=\\x\\ 9 # "'
    try:
        engine.start()
        engine.submit(f"watch I 1 '{hostile}'")
        url = f"http://127.0.0.1:{server.port}/metrics"
        deadline = time.monotonic() + 15
        got = samples(scrape(url)[0])
        while not any(key[0] == "rac_value" for key in got):
            assert time.monotonic() < deadline, "the value never reached /metrics"
            engine.outbox.drain()
            time.sleep(0.05)  # between scrapes, until the deadline
            got = samples(scrape(url)[0])
        values = [key for key in got if key[0] == "rac_value"]
        assert len(values) == 1  # no sample was made of the label
        assert dict(values[0][1])["label"] == hostile
        assert got[values[0]] == 1.0
    finally:
        engine.stop()
        server.stop()


# ------------------------------------------------------------------ refused before anything


def test_a_port_in_use_is_one_line_before_polling(env: dict[str, str], tmp_path: Path) -> None:
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = cli(env, "watch", "I", "1", "--count", "1", "--metrics", f"127.0.0.1:{port}")
    assert result.returncode == 2
    assert "--metrics cannot serve" in one_error_line(result)
    assert result.stdout == ""


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (("watch", "I", "1", "--metrics", "nine"), "--metrics takes [HOST:]PORT"),
        (("get", "I", "1", "--metrics", "9108"), "get has no option '--metrics'"),
        (("--metrics", "9108", "put", "I", "1", "2"), "not put"),
    ],
)
def test_metrics_where_it_means_nothing_is_refused(
    env: dict[str, str], args: tuple[str, ...], says: str
) -> None:
    result = cli(env, *args)
    assert result.returncode == 2
    assert says in one_error_line(result)
