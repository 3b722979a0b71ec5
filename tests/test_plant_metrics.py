"""``--metrics``: the real CLI as a subprocess serving ``/metrics``, scraped with a plain
HTTP client and read back with Prometheus's own text parsers."""

from __future__ import annotations

import re
import time
import urllib.request
from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.commands.plant import parse_metrics_address
from rac_console.engine import Engine
from rac_console.plant.metrics import MetricsBoard
from rac_console.plant.metrics_server import MetricsServer
from rac_console.protocol import InputError
from tests.support.drivers import Running, cli, one_error_line
from tests.support.servers import CLOSE, RecordingServer

prometheus = pytest.importorskip("prometheus_client")
from prometheus_client.openmetrics.parser import (  # noqa: E402
    text_string_to_metric_families as openmetrics_families,
)
from prometheus_client.parser import text_string_to_metric_families  # noqa: E402

pytestmark = pytest.mark.slow
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
    assert got["rac_poll_interval_seconds", labels(target="sim")] == 0.1
    ok = got["rac_reads_total", labels(target="sim", result="ok")]
    assert ok >= 3 and got["rac_reads_total", labels(target="sim", result="no_reply")] == 0
    # The counter counts on: a later page (made at most once a second) has more.
    deadline = time.monotonic() + 20
    while samples(scrape(url)[0])["rac_reads_total", labels(target="sim", result="ok")] <= ok:
        assert time.monotonic() < deadline, "the counter never counted on"
        time.sleep(0.2)  # between scrapes, until the deadline

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


def test_control_characters_in_a_label_are_escaped_not_sent() -> None:
    """prometheus-client escapes quotes, backslashes and newlines; ESC, BEL and C1 would
    reach the terminal of whoever curls the page."""
    board = MetricsBoard()
    server = MetricsServer(parse_metrics_address("127.0.0.1:0"), board)
    hostile = "\x1b]0;owned\x07\x1b[2J\u009b31m\u202e"
    try:
        board.set_value("sim", "I1", hostile, [("", 1.0)])
        text, _ = scrape(f"http://127.0.0.1:{server.port}/metrics")
    finally:
        server.stop()
    assert not [c for c in text if (ord(c) < 0x20 and c != "\n") or 0x7F <= ord(c) < 0xA0]
    assert "\u202e" not in text
    got = samples(text)
    label = dict(next(key for key in got if key[0] == "rac_value")[1])["label"]
    assert label == "\\x1b]0;owned\\x07\\x1b[2J\\x9b31m\\u202e"


def raw_request(port: int, request: bytes) -> bytes:
    """What the server answers ``request`` with, until it closes."""
    import socket

    with socket.create_connection(("127.0.0.1", port), timeout=20) as sock:
        sock.sendall(request)
        answer = b""
        while chunk := sock.recv(65536):
            answer += chunk
    return answer


@pytest.mark.parametrize(
    ("request_bytes", "status"),
    [
        (b"GET /metrics HTTP/1.1\r\nHost: x\r\n\r\n", b"200"),
        (b"HEAD /metrics HTTP/1.1\r\n\r\n", b"200"),
        (b"POST /metrics HTTP/1.1\r\nContent-Length: 0\r\n\r\n", b"405"),
        (b"GET /static/ HTTP/1.1\r\n\r\n", b"404"),
        (b"GET /metrics HTTP/1.1\r\nX: " + b"a" * 10_000 + b"\r\n\r\n", b"431"),
        (b"\x16\x03\x01 hello TLS\r\n\r\n", b"400"),
        (b"GET /metrics HTTP/1.1\r\n", b""),  # a head never finished: closed, unanswered
    ],
    ids=["get", "head", "post", "elsewhere", "a long head", "not http", "unfinished"],
)
def test_the_metrics_server_answers_only_what_it_serves(
    request_bytes: bytes, status: bytes
) -> None:
    server = MetricsServer(parse_metrics_address("127.0.0.1:0"), MetricsBoard())
    try:
        answer = raw_request(server.port, request_bytes)
    finally:
        server.stop()
    assert answer.split(b" ", 2)[1:2] == ([status] if status else [])
    if request_bytes.startswith(b"HEAD"):
        assert answer.endswith(b"\r\n\r\n")  # the head only


@pytest.mark.parametrize(
    "accept",
    [
        b"application/openmetrics-text; version=abc",  # prometheus-client's own parser chokes
        b"text/plain; version=2.\nX-Injected: yes",  # a bare LF inside the header
        b"application/openmetrics-text; version=1.0.0; x=" + b"y" * 2000,
    ],
    ids=["a version that is no number", "a header smuggled in", "a long one"],
)
def test_an_odd_accept_header_gets_one_of_two_pages_and_the_server_goes_on(
    accept: bytes,
) -> None:
    server = MetricsServer(parse_metrics_address("127.0.0.1:0"), MetricsBoard())
    try:
        odd = raw_request(server.port, b"GET /metrics HTTP/1.1\r\nAccept: " + accept + b"\r\n\r\n")
        after = raw_request(server.port, b"GET /metrics HTTP/1.1\r\n\r\n")
    finally:
        server.stop()
    head = odd.split(b"\r\n\r\n", 1)[0]
    assert head.startswith(b"HTTP/1.1 200")
    assert b"X-Injected" not in head and b"version=abc" not in head and b"yyyy" not in head
    content_type = next(ln for ln in head.split(b"\r\n") if ln.startswith(b"Content-Type"))
    assert content_type in (
        b"Content-Type: text/plain; version=0.0.4; charset=utf-8",
        b"Content-Type: application/openmetrics-text; version=1.0.0; charset=utf-8",
    )
    assert after.startswith(b"HTTP/1.1 200")  # the server is still there


def test_any_ipv6_address_takes_ipv4_too_where_the_system_can() -> None:
    import socket

    if not (socket.has_ipv6 and socket.has_dualstack_ipv6()):
        pytest.skip("no dual-stack IPv6 here")
    try:
        server = MetricsServer(parse_metrics_address("[::]:0"), MetricsBoard())
    except InputError as exc:
        pytest.skip(f"cannot bind [::] here: {exc}")
    try:
        assert raw_request(server.port, b"GET /metrics HTTP/1.1\r\n\r\n").startswith(
            b"HTTP/1.1 200"
        )
    finally:
        server.stop()


def proc_status(pid: int, field: str) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(f"{field}:"):
            return int(line.split()[1])
    raise AssertionError(f"no {field}")


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
def test_a_thousand_idle_connections_take_no_thread_and_polling_goes_on(
    env: dict[str, str], running: list[Running]
) -> None:
    import resource
    import socket

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard != resource.RLIM_INFINITY and hard < 1200:
        pytest.skip(f"the test needs 1,200 descriptors, this machine allows {hard}")
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(soft, 1200), hard))
    watch = Running(env, "--json", "watch", "I", "1", "--every", "0.05", "--metrics", "0")
    running.append(watch)
    url = serving(watch)
    port = int(url.rsplit(":", 1)[1].split("/")[0])
    watch.wait_for("polling", lambda: len(watch.out) >= 3)
    pid = watch.process.pid
    threads_before = proc_status(pid, "Threads")
    idle: list[socket.socket] = []
    try:
        for _ in range(1000):
            sock = socket.socket()
            sock.setblocking(False)
            sock.connect_ex(("127.0.0.1", port))  # in progress: the kernel queues it
            idle.append(sock)
        seen = len(watch.out)
        watch.wait_for("polling on", lambda: len(watch.out) >= seen + 40, deadline=60)
        threads = proc_status(pid, "Threads")
        peak_mb = proc_status(pid, "VmHWM") / 1024
    finally:
        for sock in idle:
            sock.close()
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))
    assert threads <= threads_before, f"{threads_before} threads, then {threads}"
    assert peak_mb < 150, f"peak RSS {peak_mb:.0f} MB"
    # Gone, they leave the server as it was: a scrape is answered.
    deadline = time.monotonic() + 30
    while True:
        try:
            assert "rac_value" in scrape(url)[0]
            break
        except OSError:
            assert time.monotonic() < deadline, "no scrape answered after the idle ones left"
            time.sleep(0.2)  # between tries, until the deadline
    assert watch.stop() == 0


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
        # The command's own words are refused before anything is said to be served.
        (("--metrics", "0", "watch", "ZZ", "1"), "unknown variable type"),
    ],
)
def test_metrics_where_it_means_nothing_is_refused(
    env: dict[str, str], args: tuple[str, ...], says: str
) -> None:
    result = cli(env, *args)
    assert result.returncode == 2
    assert says in one_error_line(result)
