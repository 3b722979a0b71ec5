"""Feeding the plant over MQTT: the real CLI as a subprocess, a real mosquitto started
here (127.0.0.1, a free port), and a simulator on a thread of the test's whose values the
test changes itself.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from rac_console.commands.plant import parse_mqtt_address
from rac_console.protocol import KINDS, VT, Variant
from rac_console.session import Session
from rac_console.sim.thread import SimulatorThread
from tests.support.brokers import Broker, Cable, Subscriber
from tests.support.drivers import Running, cli, one_error_line
from tests.support.fixtures import needs_mosquitto
from tests.support.servers import RecordingServer, Valve, fixed_reply

pytestmark = [needs_mosquitto, pytest.mark.slow]

#: ASCII, as RAC's wire is: JSON's quotes and braces, terminal escapes, MQTT's wildcards.
HOSTILE = '"},"value":666,"x":"\x1b[2J\x1b]0;owned\x07{#}+/\\'


@pytest.fixture
def sim() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


def put(sim: SimulatorThread, kind: str, index: int, value: Variant) -> None:
    """Change a value on the simulator over a session of the test's own."""
    session = Session(sim.host, sim.port, timeout=5)
    try:
        assert session.put(KINDS[kind], index, value).response.ok
    finally:
        session.close()


# ------------------------------------------------------------------ topics and payloads


def test_watched_values_arrive_on_retained_topics_with_their_fields(
    env: dict[str, str], broker: Broker
) -> None:
    result = cli(
        env, "watch", "I", "1", "P", "1", "IO", "3", "S", "1", "--count", "2",
        "--mqtt", f"{broker.url}/plant/line2",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "publishing sim's watched values to" in result.stderr
    # A subscriber that comes afterwards gets them all: they are retained.
    late = Subscriber(broker.port, "plant/#")
    try:
        topics = ("I1", "P1", "IO3", "S1", "status")
        late.wait_for(
            "every topic", lambda s: all(f"plant/line2/sim/{t}" in s.last for t in topics)
        )
        retained = {topic for topic, _, retain in late.messages if retain}
        assert retained >= {f"plant/line2/sim/{t}" for t in topics}
        i1 = json.loads(late.last["plant/line2/sim/I1"])
        assert i1["value"] == 1 and i1["vartype"] == "VT_I4" and i1["status"] == "OK"
        assert i1["target"] == "sim" and i1["variable"] == "I1"
        assert i1["time"].endswith("Z")
        p1 = json.loads(late.last["plant/line2/sim/P1"])["value"]
        assert p1 == {
            "X": 350.0,
            "Y": 0.0,
            "Z": 450.0,
            "Rx": 180.0,
            "Ry": 0.0,
            "Rz": 180.0,
            "Fig": 5.0,
        }
        assert json.loads(late.last["plant/line2/sim/IO3"])["value"] in (True, False)
        assert json.loads(late.last["plant/line2/sim/S1"])["value"] == "RC8 simulator"
        # The watch ended cleanly: its status says so (no last will needed).
        assert late.last["plant/line2/sim/status"] == b"offline"
    finally:
        late.close()


def test_a_change_is_published_and_an_unchanged_value_is_not_sent_again(
    env: dict[str, str], broker: Broker, subscriber: Subscriber, sim: SimulatorThread,
    running: list[Running],
) -> None:  # fmt: skip
    watch = Running(
        env, "-H", sim.host, "-p", str(sim.port), "watch", "I", "7", "I", "8",
        "--every", "0.05", "--mqtt", f"{broker.url}/plant",
    )  # fmt: skip
    running.append(watch)
    topic = f"plant/{sim.host}:{sim.port}/I7"
    subscriber.wait_for("the first value", subscriber.has_value(topic, 0))
    watch.wait_for("ten cycles more", lambda: len(watch.out) >= 10)
    assert [t for t, _, _ in subscriber.messages].count(topic) == 1
    put(sim, "I", 7, Variant(VT.I4, 41))
    subscriber.wait_for("the change", subscriber.has_value(topic, 41))
    assert watch.stop() == 0
    assert sum("publishing" in line for line in watch.err) == 1  # said once


def test_the_last_will_says_offline_when_the_watch_is_killed(
    env: dict[str, str], broker: Broker, subscriber: Subscriber, running: list[Running]
) -> None:
    watch = Running(env, "watch", "I", "1", "--every", "0.2", "--mqtt", f"{broker.url}/plant")
    running.append(watch)
    subscriber.wait_for("online", lambda s: s.last.get("plant/sim/status") == b"online")
    watch.process.kill()  # no clean end: only the broker can say it
    watch.process.wait(20)
    subscriber.wait_for("the last will", lambda s: s.last.get("plant/sim/status") == b"offline")


def test_a_broker_restarted_mid_watch_loses_no_change_and_never_stalls_polling(
    env: dict[str, str], broker: Broker, sim: SimulatorThread, running: list[Running]
) -> None:
    watch = Running(
        env, "-H", sim.host, "-p", str(sim.port), "--json", "watch", "I", "20", "I", "21",
        "--every", "0.05", "--mqtt", f"{broker.url}/plant",
    )  # fmt: skip
    running.append(watch)
    base = f"plant/{sim.host}:{sim.port}"
    first = Subscriber(broker.port, "plant/#")
    first.wait_for("the first values", first.has_value(f"{base}/I20", 0))
    first.close()

    broker.stop()
    watch.wait_for("the loss said", lambda: any("lost the MQTT broker" in e for e in watch.err))
    put(sim, "I", 20, Variant(VT.I4, 2020))  # changed while the broker is away
    # Polling goes on without the broker: the watch's own lines show the change.
    watch.wait_for(
        "the change polled",
        lambda: any(json.loads(line)["values"]["I20"] == 2020 for line in watch.out),
    )
    broker.start()  # the same port; it lost every retained message (no persistence)
    back = Subscriber(broker.port, "plant/#")
    try:
        back.wait_for("the change kept over the outage", back.has_value(f"{base}/I20", 2020))
        back.wait_for("the unchanged value too", back.has_value(f"{base}/I21", 0))
        put(sim, "I", 21, Variant(VT.I4, 2121))  # and changes after it is back
        back.wait_for("a change after", back.has_value(f"{base}/I21", 2121))
        assert back.last[f"{base}/status"] == b"online"
    finally:
        back.close()
    assert watch.stop() == 0
    said = "\n".join(watch.err)
    assert said.count("lost the MQTT broker") == 1
    assert "cannot reach" not in said  # an outage is one line, whatever the retries
    assert said.count("the MQTT broker is back") == 1
    assert "Traceback" not in said


def test_a_hostile_controller_string_arrives_intact_and_harmless(
    env: dict[str, str],
    broker: Broker,
    subscriber: Subscriber,
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording(fixed_reply(b"0,8," + HOSTILE.encode("utf-8") + b"\r"))
    result = cli(
        env, *server.args, "--json", "watch", "S", "4", "--count", "1",
        "--mqtt", f"{broker.url}/plant",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    shown = json.loads(result.stdout)["values"]["S4"]  # what --json says the string is
    base = f"plant/127.0.0.1:{server.port}"
    topic = f"{base}/S4"
    subscriber.wait_for("the string", lambda s: topic in s.last)
    payload = subscriber.last[topic]
    assert payload.isascii() and b"\x1b" not in payload and b"\x07" not in payload
    data = json.loads(payload)
    assert data["value"] == shown and "\x1b[2J" in shown  # intact, as --json gives it
    assert set(data) == {"value", "vartype", "status", "time", "target", "variable"}
    # No topic other than the variable's and the status was made of it.
    assert {t for t, _, _ in subscriber.messages} <= {topic, f"{base}/status"}
    assert "\x1b" not in result.stderr


def test_a_reading_taken_before_the_broker_answered_is_published_at_the_end(
    env: dict[str, str], broker: Broker, subscriber: Subscriber, sim: SimulatorThread,
    running: list[Running],
) -> None:  # fmt: skip
    """A ``watch --count 1`` has its reading before a slow broker has answered the
    CONNECT: the end waits for the connection, then publishes it and says offline."""
    put(sim, "I", 5, Variant(VT.I4, 55))
    gate = Valve("127.0.0.1", broker.port)  # the broker's CONNACK held until the reading is shown
    gate.shut()
    try:
        watch = Running(
            env, "-H", sim.host, "-p", str(sim.port), "--json", "watch", "I", "5",
            "--count", "1", "--mqtt", f"mqtt://127.0.0.1:{gate.port}/plant",
        )  # fmt: skip
        running.append(watch)
        watch.wait_for("the reading", lambda: len(watch.out) >= 1)
        gate.open()
        assert watch.process.wait(20) == 0, watch.err
        base = f"plant/{sim.host}:{sim.port}"
        subscriber.wait_for("the reading", subscriber.has_value(f"{base}/I5", 55))
        subscriber.wait_for("offline", lambda s: s.last.get(f"{base}/status") == b"offline")
    finally:
        gate.close()


def test_nothing_received_from_the_broker_reaches_the_controller(
    env: dict[str, str], broker: Broker, subscriber: Subscriber, sim: SimulatorThread,
    running: list[Running], tmp_path: Path,
) -> None:  # fmt: skip
    record = tmp_path / "wire.jsonl"
    watch = Running(
        env, "-H", sim.host, "-p", str(sim.port), "--record", str(record), "watch", "I", "30",
        "--every", "0.05", "--mqtt", f"{broker.url}/plant",
    )  # fmt: skip
    running.append(watch)
    base = f"plant/{sim.host}:{sim.port}"
    subscriber.wait_for("the value", subscriber.has_value(f"{base}/I30", 0))
    for topic in (f"{base}/I30", f"{base}/I30/set", f"{base}/set", f"{base}/I30/put"):
        for payload in (b"99", b'{"value": 99}', b"PUT:RC8:30:I:3,99"):
            subscriber.client.publish(topic, payload, qos=1).wait_for_publish(5)
    watch.wait_for("twenty cycles more", lambda: len(watch.out) >= 20)
    assert watch.stop() == 0
    session = Session(sim.host, sim.port, timeout=5)
    try:
        assert session.get(KINDS["I"], 30).response.variant == Variant(VT.I4, 0)
    finally:
        session.close()
    sent = [json.loads(line) for line in record.read_text().splitlines()]
    assert sent and all("PUT" not in frame.get("text", "") for frame in sent)


# ------------------------------------------------------------------ refusals, said once


def test_a_broker_that_refuses_is_one_line_and_polling_goes_on(
    env: dict[str, str], tmp_path: Path
) -> None:
    passwords = tmp_path / "passwords"
    subprocess.run(
        ["mosquitto_passwd", "-b", "-c", str(passwords), "rac", "right-password"], check=True
    )
    broker = Broker(tmp_path, ("allow_anonymous false", f"password_file {passwords}")).start()
    try:
        environment = env | {"RAC_MQTT_USERNAME": "rac", "RAC_MQTT_PASSWORD": "wrong-password"}
        result = cli(
            environment, "watch", "I", "1", "--every", "0.2", "--count", "8",
            "--mqtt", f"{broker.url}/plant",
        )  # fmt: skip
    finally:
        broker.stop()
    assert result.returncode == 0, result.stderr
    assert len(result.stdout.splitlines()) == 8  # every cycle polled and shown
    refusals = [line for line in result.stderr.splitlines() if "refused" in line]
    assert len(refusals) == 1, result.stderr
    assert "wrong-password" not in result.stderr + result.stdout


def test_the_right_password_from_the_config_file_is_used_and_never_printed(
    env: dict[str, str], tmp_path: Path
) -> None:
    passwords = tmp_path / "passwords"
    subprocess.run(
        ["mosquitto_passwd", "-b", "-c", str(passwords), "rac", "s3cret-Pa55"], check=True
    )
    broker = Broker(tmp_path, ("allow_anonymous false", f"password_file {passwords}")).start()
    config = Path(env["XDG_CONFIG_HOME"]) / "rac-console" / "config.toml"
    config.parent.mkdir(parents=True)
    config.write_text('[mqtt]\nusername = "rac"\npassword = "s3cret-Pa55"\n')
    try:
        result = cli(env, "watch", "I", "1", "--count", "2", "--mqtt", f"{broker.url}/plant")
        late = Subscriber(broker.port, "plant/#", user=("rac", "s3cret-Pa55"))
        try:  # anonymous is refused: read as the user
            late.wait_for("the value", late.has_value("plant/sim/I1", 1))
        finally:
            late.close()
    finally:
        broker.stop()
    assert result.returncode == 0, result.stderr
    assert "s3cret-Pa55" not in result.stderr + result.stdout
    assert "refused" not in result.stderr


def test_a_denied_topic_is_one_line_and_polling_goes_on(
    env: dict[str, str], tmp_path: Path
) -> None:
    acl = tmp_path / "acl"
    acl.write_text("topic write plant/sim/status\ntopic write plant/sim/I1\n")
    broker = Broker(tmp_path, ("allow_anonymous true", f"acl_file {acl}")).start()
    try:
        result = cli(
            env, "watch", "I", "1", "I", "2", "--every", "0.2", "--count", "6",
            "--mqtt", f"{broker.url}/plant",
        )  # fmt: skip
    finally:
        broker.stop()
    assert result.returncode == 0, result.stderr
    assert len(result.stdout.splitlines()) == 6
    denied = [line for line in result.stderr.splitlines() if "did not take" in line]
    assert len(denied) == 1 and "plant/sim/I2" in denied[0], result.stderr


def test_a_broker_that_is_not_there_is_one_line_and_polling_goes_on(
    env: dict[str, str],
) -> None:
    from tests.support.brokers import free_port

    result = cli(
        env, "watch", "I", "1", "--every", "0.2", "--count", "6",
        "--mqtt", f"mqtt://127.0.0.1:{free_port()}/plant",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert len(result.stdout.splitlines()) == 6
    assert len([e for e in result.stderr.splitlines() if "cannot reach" in e]) == 1


# ------------------------------------------------------------------ refused before anything


@pytest.mark.parametrize(
    ("url", "says"),
    [
        ("mqtt://rac:hunter2@127.0.0.1/plant", "no user or password"),
        ("mqtt://rac:4711/hunter2@127.0.0.1:1883/line2", "no user or password"),
        ("mqtt://127.0.0.1", "give a topic prefix"),
        ("mqtt://127.0.0.1/plant/+", "reserve"),
        ("http://127.0.0.1/plant", "mqtt:// or mqtts://"),
        ("mqtt://127.0.0.1:99999/plant", "port"),
    ],
)
def test_an_address_that_cannot_be_used_is_refused_before_polling(
    env: dict[str, str], url: str, says: str
) -> None:
    result = cli(env, "watch", "I", "1", "--count", "1", "--mqtt", url)
    assert result.returncode == 2
    line = one_error_line(result)
    assert says in line and "hunter2" not in line and "4711" not in line
    assert result.stdout == ""


def test_without_the_extra_the_message_says_how_to_get_it(
    env: dict[str, str], tmp_path: Path
) -> None:
    shadow = tmp_path / "shadow"
    for package in ("paho", "prometheus_client"):
        (shadow / package).mkdir(parents=True)
        (shadow / package / "__init__.py").write_text("raise ImportError('not installed')\n")
    environment = env | {"PYTHONPATH": os.pathsep.join([str(shadow), env.get("PYTHONPATH", "")])}
    mqtt = cli(environment, "watch", "I", "1", "--mqtt", "mqtt://127.0.0.1/plant")
    assert mqtt.returncode == 2
    assert 'pip install "rac-console[mqtt]"' in one_error_line(mqtt)
    metrics = cli(environment, "watch", "I", "1", "--metrics", "0")
    assert metrics.returncode == 2
    assert 'pip install "rac-console[metrics]"' in one_error_line(metrics)


def until(what: str, holds: Callable[[], bool], deadline: float = 10) -> None:
    """Wait for a condition that nothing signals, looking every 20 ms."""
    end = time.monotonic() + deadline
    while not holds():
        assert time.monotonic() < end, f"timed out waiting for {what}"
        time.sleep(0.02)


def test_a_change_sent_into_a_pulled_cable_does_not_end_up_over_the_latest(
    broker: Broker,
) -> None:
    """paho keeps what it sent unacknowledged and sends it again after reconnecting;
    the feed sends the latest of every topic again too. When the latest goes first
    (here: the feed's thread hands it over while paho's thread is still telling the
    user the broker is back, as with a slow terminal), the broker must not be left
    with the old value."""
    from rac_console.commands.plant import Credentials, parse_mqtt_address
    from rac_console.plant.mqtt import MqttFeed

    cable = Cable(broker.port)
    said: list[str] = []
    latest = b'{"value": 3}'
    handed = threading.Event()  # the feed's thread handed the latest to paho

    def say(text: str) -> None:
        said.append(text)
        if text.startswith("the MQTT broker is back"):
            handed.wait(10)  # paho's thread, in its on_connect: a slow terminal

    address = parse_mqtt_address(f"mqtt://127.0.0.1:{cable.port}/plant")
    feed = MqttFeed(address, Credentials(), "sim", say)
    publish = feed._client.publish

    def noting(topic: str, payload: bytes, *args: Any, **kwargs: Any) -> Any:
        info = publish(topic, payload, *args, **kwargs)
        if payload == latest:
            handed.set()
        return info

    feed._client.publish = noting
    topic = "plant/sim/I1"
    watching = Subscriber(broker.port, "plant/#")
    try:
        feed.update("I1", b'{"value": 1}')
        feed.start()
        watching.wait_for("the first value", watching.has_value(topic, 1))
        cable.pull()
        feed.update("I1", b'{"value": 2}')  # into the void: never acknowledged
        until("the change sent", lambda: b'{"value": 2}' in cable.swallowed)
        cable.cut()  # the keepalive's end, without waiting for it
        until("the loss seen", lambda: not feed.connected)
        feed.update("I1", latest)  # changed while the broker is away
        cable.restore()
        watching.wait_for("back online", lambda s: s.last.get("plant/sim/status") == b"online")
        watching.wait_for("the latest", watching.has_value(topic, 3))
    finally:
        feed.stop()  # offline goes last: the broker has taken everything before it
        cable.close()
    try:
        watching.wait_for("offline", lambda s: s.last.get("plant/sim/status") == b"offline")
        sent = [json.loads(p)["value"] for t, p, _ in watching.messages if t == topic]
    finally:
        watching.close()
    assert sent[-1] == 3, f"the broker is left with {sent[-1]} (all it got: {sent})"
    assert sum(line.startswith("the MQTT broker is back") for line in said) == 1, said


def test_a_profile_and_a_cell_publish_from_the_config_file(
    env: dict[str, str], broker: Broker, sim: SimulatorThread, request: pytest.FixtureRequest
) -> None:
    subscriber = Subscriber(broker.port, "#")
    config = Path(env["XDG_CONFIG_HOME"]) / "rac-console" / "config.toml"
    config.parent.mkdir(parents=True)
    other = SimulatorThread().__enter__()  # a cell's targets are two controllers
    request.addfinalizer(lambda: other.__exit__(None, None, None))
    config.write_text(
        f'[target.cell3]\nhost = "{sim.host}"\nport = {sim.port}\n'
        f'publish = "{broker.url}/line3"\n'
        f'[target.cell4]\nhost = "{other.host}"\nport = {other.port}\n'
        f'[cell.line2]\ntargets = ["cell3", "cell4"]\npublish = "{broker.url}/line2"\n'
    )
    one = cli(env, "-H", "cell3", "watch", "I", "1", "--count", "2")
    assert one.returncode == 0, one.stderr
    subscriber.wait_for("the profile's topic", subscriber.has_value("line3/cell3/I1", 1))
    both = cli(env, "--cell", "line2", "watch", "I", "2", "--count", "2")
    assert both.returncode == 0, both.stderr
    for name in ("cell3", "cell4"):  # the cell's publish wins over cell3's own
        subscriber.wait_for(name, subscriber.has_value(f"line2/{name}/I2", 250))
    assert "line3/cell3/I2" not in subscriber.last
    subscriber.close()


# ------------------------------------------------------------------ mqtts://


def make_certificates(folder: Path) -> tuple[Path, Path, Path]:
    """A CA of the test's own and a certificate it signed for 127.0.0.1 (openssl)."""
    ca_key, ca, key, request, certificate = (
        folder / name for name in ("ca.key", "ca.pem", "server.key", "server.csr", "server.pem")
    )
    extensions = folder / "san.cnf"
    extensions.write_text("subjectAltName = IP:127.0.0.1\n")

    def openssl(*args: str) -> None:
        subprocess.run(["openssl", *args], check=True, capture_output=True, timeout=60)

    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj",
            "/CN=rac test CA", "-keyout", str(ca_key), "-out", str(ca))  # fmt: skip
    openssl("req", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=127.0.0.1",
            "-keyout", str(key), "-out", str(request))  # fmt: skip
    openssl("x509", "-req", "-in", str(request), "-CA", str(ca), "-CAkey", str(ca_key),
            "-CAcreateserial", "-days", "2", "-extfile", str(extensions),
            "-out", str(certificate))  # fmt: skip
    return ca, certificate, key


@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs openssl for the certificates")
def test_mqtts_with_the_ca_file_given_and_refused_without_it(
    env: dict[str, str], tmp_path: Path
) -> None:
    ca, certificate, key = make_certificates(tmp_path)
    tls = ("allow_anonymous true", f"cafile {ca}", f"certfile {certificate}", f"keyfile {key}")
    broker = Broker(tmp_path, tls).start()
    url = f"mqtts://127.0.0.1:{broker.port}/plant"
    try:
        trusted = cli(
            env | {"RAC_MQTT_CA_FILE": str(ca)}, "watch", "I", "1", "--count", "2", "--mqtt", url
        )
        import paho.mqtt.client as mqtt
        from paho.mqtt.enums import CallbackAPIVersion

        got: list[bytes | bytearray] = []
        reader = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
        reader.tls_set(ca_certs=str(ca))
        reader.on_message = lambda c, u, m: got.append(m.payload)
        reader.on_connect = lambda c, u, f, r, p: c.subscribe("plant/sim/I1", 1)
        reader.connect("127.0.0.1", broker.port)
        reader.loop_start()
        try:
            until("the value over TLS", lambda: bool(got))
        finally:
            reader.loop_stop()
            reader.disconnect()
        assert json.loads(got[-1])["value"] == 1
        # Without the CA, the system's certificates do not know it: one line, polling on.
        untrusted = cli(env, "watch", "I", "1", "--every", "0.2", "--count", "6", "--mqtt", url)
    finally:
        broker.stop()
    assert trusted.returncode == 0, trusted.stderr
    assert "cannot reach" not in trusted.stderr
    assert untrusted.returncode == 0, untrusted.stderr
    assert len(untrusted.stdout.splitlines()) == 6
    said = [e for e in untrusted.stderr.splitlines() if "MQTT broker" in e]
    assert len(said) == 1
    assert "certificate does not verify" in said[0] and "RAC_MQTT_CA_FILE" in said[0]
    missing = cli(
        env | {"RAC_MQTT_CA_FILE": str(tmp_path / "nowhere.pem")}, "watch", "I", "1",
        "--count", "1", "--mqtt", url,
    )  # fmt: skip
    assert missing.returncode == 2 and missing.stdout == ""  # refused before polling
    assert "nowhere.pem" in one_error_line(missing)
    not_a_certificate = tmp_path / "notes.txt"
    not_a_certificate.write_text("not a certificate\n")
    garbage = cli(
        env | {"RAC_MQTT_CA_FILE": str(not_a_certificate)}, "watch", "I", "1",
        "--count", "1", "--mqtt", url,
    )  # fmt: skip
    assert garbage.returncode == 2 and "no certificate TLS can use" in one_error_line(garbage)


def test_mqtts_to_a_plain_mqtt_port_is_said_to_be_no_tls(
    env: dict[str, str], broker: Broker
) -> None:
    result = cli(
        env, "watch", "I", "1", "--every", "0.2", "--count", "6",
        "--mqtt", f"mqtts://127.0.0.1:{broker.port}/plant",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert len(result.stdout.splitlines()) == 6
    said = [line for line in result.stderr.splitlines() if "MQTT" in line]
    assert len(said) == 1, result.stderr
    assert "no TLS handshake with the MQTT broker" in said[0] and "mqtts port?" in said[0]


def test_an_address_that_is_no_mqtt_broker_is_one_line_and_polling_goes_on(
    env: dict[str, str],
) -> None:
    """A web server where the broker was meant: it answers the CONNECT with HTTP and
    hangs up. Said once (it was silent before: only a refused TCP connection was said)."""
    import socket
    import threading

    server = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def answer() -> None:
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except TimeoutError:
                continue
            with conn:
                conn.settimeout(5)
                with contextlib.suppress(OSError):
                    conn.recv(1024)
                    conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")

    worker = threading.Thread(target=answer, daemon=True)
    worker.start()
    try:
        port = server.getsockname()[1]
        result = cli(
            env, "watch", "I", "1", "--every", "0.2", "--count", "8",
            "--mqtt", f"mqtt://127.0.0.1:{port}/plant",
        )  # fmt: skip
    finally:
        stop.set()
        worker.join(5)
        server.close()
    assert result.returncode == 0, result.stderr
    assert len(result.stdout.splitlines()) == 8
    said = [line for line in result.stderr.splitlines() if "no MQTT answer" in line]
    assert len(said) == 1, result.stderr
    assert "Traceback" not in result.stderr


def test_after_connect_the_values_go_under_the_new_targets_name(
    tmp_path: Path, broker: Broker, subscriber: Subscriber, sim: SimulatorThread
) -> None:
    """The built-in simulator first, then ``connect`` to another controller: its values
    must not be published as the first one's."""
    from rac_console.engine import Engine

    put(sim, "I", 1, Variant(VT.I4, 4242))
    address = parse_mqtt_address(f"{broker.url}/plant")
    engine = Engine(None, interval=0.05, timeout=2.0, publish=address)
    engine.start()
    try:
        engine.submit("watch I 1")
        subscriber.wait_for("the simulator's I1", subscriber.has_value("plant/sim/I1", 1))
        engine.submit(f"connect {sim.host}:{sim.port}")
        other = f"plant/{sim.host}:{sim.port}/I1"
        subscriber.wait_for("the other controller's I1", subscriber.has_value(other, 4242))
    finally:
        engine.stop()
    assert all(
        json.loads(payload).get("value") != 4242
        for topic, payload, _ in subscriber.messages
        if topic == "plant/sim/I1"
    )
    subscriber.wait_for("sim offline", lambda s: s.last.get("plant/sim/status") == b"offline")
