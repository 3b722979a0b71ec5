"""A console served to a browser reaches its controller and nothing else, whatever the
config file says: the settings that reach the network or the files (a target's or a
cell's ``publish``, the ``[mqtt]`` table with its CA file) are not read there, and the
console says so once. Judged from the machine's side: a listener at each ``publish``
address that no served session reaches, while the same config in a console that is not
served does reach it; a session that starts and polls its controller whatever CA file
the config names."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from rac_console.commands.config_keys import NAMED_TABLES, PLAIN_TABLES, withheld_notice, withhold
from rac_console.commands.plant import CA_FILE_ENV, PASSWORD_ENV, USERNAME_ENV, Credentials
from rac_console.commands.reach import Reach
from rac_console.engine.setup.config import load_config
from rac_console.engine.setup.where import Where
from tests.support.drivers import RAC, Running
from tests.support.servers import RecordingServer, fixed_reply
from tests.support.serving import consoles_of, open_console, start_serve, until

pytest.importorskip("textual_serve", reason="needs the extra web")
pytest.importorskip("paho.mqtt.client", reason="needs the extra mqtt (the control publishes)")

#: What the served console says of the settings it did not read.
NOT_READ = "not read in a served console"
#: A line of the frame log, where the console's alerts stay in order.
FRAME_LOG_LINE = re.compile(r"│\d\d:\d\d:\d\d\.\d{3} ")


def hostile_config(
    ca_file: Path, controllers: tuple[int, int], target_broker: int, cell_broker: int
) -> str:
    """Every setting of the config file that reaches the network or the files, set."""
    first, second = controllers
    return f"""
[mqtt]
username = "plant"
password = "secret"
ca_file = '{ca_file}'  # a literal string: a Windows path holds backslashes
keepalive = 5

[target.pubA]
host = "127.0.0.1"
port = {first}
publish = "mqtt://127.0.0.1:{target_broker}/line2"

[target.pubB]
host = "127.0.0.1"
port = {second}
publish = "mqtt://127.0.0.1:{target_broker}/line2"

[cell.line2]
targets = ["pubA", "pubB"]
watch = ["pubA I 1", "pubB I 1"]
publish = "mqtt://127.0.0.1:{cell_broker}/cell"
"""


def a_ca_file(folder: Path) -> Path:
    """A CA certificate TLS can use (openssl, an EC key: made in a moment)."""
    key, ca = folder / "ca.key", folder / "ca.pem"
    subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
         "-nodes", "-keyout", str(key), "-out", str(ca), "-days", "1", "-subj", "/CN=test-ca"],
        check=True, capture_output=True, timeout=30,
    )  # fmt: skip
    return ca


GET_I1 = b"GET:RC8:1:I:"


def polled(controller: RecordingServer, after: int, times: int) -> bool:
    """The controller got ``times`` GETs of I 1 after its first ``after`` lines."""
    return controller.lines[after:].count(GET_I1) >= times


def served_session_polls(
    env: dict[str, str],
    running: list[Running],
    before: tuple[str, ...],
    controllers: list[RecordingServer],
) -> tuple[list[str], list[str]]:
    """A session of ``rac-console BEFORE serve``, alive until each controller has
    answered its watch of I 1 three times, then closed and its console ended: the lines
    its console's frame log and ``serve``'s standard error said of the settings not read."""
    marks = [len(c.lines) for c in controllers]
    served = start_serve(env, running, before=before)
    console = open_console(served)
    console.until("SERVED", "connected")
    if "--cell" not in before:
        console.type_line("watch I 1")
    until(
        lambda: all(polled(c, m, 3) for c, m in zip(controllers, marks, strict=True)),
        "three polls of I 1 at each controller",
    )
    shown = console.until("I1")
    console.close()
    until(lambda: consoles_of(served.running.process.pid) == [], "the console ending")
    served.running.stop()
    # What the console said (its frame log keeps each alert, in order), and what serve
    # said to the operator at its terminal, whole.
    said = [line for line in shown.splitlines() if FRAME_LOG_LINE.search(line) and NOT_READ in line]
    told = [line for line in served.running.err if NOT_READ in line]
    return said, told


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs openssl for the CA file")
def test_a_served_session_publishes_nowhere_whatever_the_config_says(
    env, running, config, recording, tmp_path: Path
) -> None:
    controllers = [recording(), recording()]
    target_broker, cell_broker = recording(fixed_reply(None)), recording(fixed_reply(None))
    ca = a_ca_file(tmp_path)
    ports = (controllers[0].port, controllers[1].port)
    config(hostile_config(ca, ports, target_broker.port, cell_broker.port))

    # The same config outside a served console does publish: the listeners would see it.
    control = Running(env, "-H", "pubA", "watch", "I", "1")
    running.append(control)
    until(lambda: target_broker.accepted > 0, "the plain watch connecting to its broker")
    control.stop()
    control = Running(env, "--cell", "line2", "watch", "I", "1")
    running.append(control)
    until(lambda: cell_broker.accepted > 0, "the plain watch connecting to the cell's broker")
    control.stop()
    seen = {"target": target_broker.connections(), "cell": cell_broker.connections()}

    # Served: one target, then the cell. Each session has polled its controllers three
    # times and ended before the listeners are asked (a connection it ever made would be
    # in their accept queue by then: connections() waits until a probe of its own is in).
    said, told = served_session_polls(env, running, ("-H", "pubA"), controllers[:1])
    assert target_broker.connections() == seen["target"], "a served session published"
    assert len(said) == 1 and len(told) == 1, (said, told)  # once each
    assert told[0].endswith(
        f"{NOT_READ}, which reaches its controller and nothing else: the config file's "
        "[mqtt] username, password, ca_file, keepalive; [target.pubA] publish; "
        "[target.pubB] publish; [cell.line2] publish"
    ), told
    said, told = served_session_polls(env, running, ("--cell", "line2"), controllers)
    assert target_broker.connections() == seen["target"], "a served cell published"
    assert cell_broker.connections() == seen["cell"], "a served cell published"
    assert len(said) == 1 and len(told) == 1, (said, told)  # once for the cell, not per target


@pytest.mark.slow
def test_a_bad_ca_file_in_the_config_stops_no_served_session(
    env, running, config, recording, tmp_path: Path
) -> None:
    """The config names a CA file that is none: a console that publishes refuses to
    start (as it should: it would publish), a served session starts and polls."""
    controllers = [recording(), recording()]
    broker = recording(fixed_reply(None))
    junk = tmp_path / "ca.pem"
    junk.write_text("not a certificate\n", encoding="utf-8")
    ports = (controllers[0].port, controllers[1].port)
    config(hostile_config(junk, ports, broker.port, broker.port))
    refused = subprocess.run(
        [*RAC, "-H", "pubA", "watch", "I", "1", "--count", "1"],
        env=env, capture_output=True, text=True, timeout=30,
    )  # fmt: skip
    assert refused.returncode == 2 and "CA file" in refused.stderr, refused.stderr
    said, told = served_session_polls(env, running, ("-H", "pubA"), controllers[:1])
    assert len(said) == 1 and "ca_file" in told[0]
    assert broker.connections() == []


def test_what_each_setting_of_the_config_file_reaches_is_declared(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The keys that reach more than the target, as a table; a served console reads
    none of them (nor their RAC_MQTT_* variables), any other place all of them."""
    tables = {**NAMED_TABLES, **PLAIN_TABLES}
    reaching = {
        (table, key): reach
        for table, keys in tables.items()
        for key, reach in keys.items()
        if reach is not Reach.TARGET
    }
    assert reaching == {
        ("target", "publish"): Reach.NETWORK,
        ("cell", "publish"): Reach.NETWORK,
        ("mqtt", "username"): Reach.NETWORK,
        ("mqtt", "password"): Reach.NETWORK,
        ("mqtt", "ca_file"): Reach.FILES,
        ("mqtt", "keepalive"): Reach.NETWORK,
    }
    path = tmp_path / "config.toml"
    path.write_text(hostile_config(tmp_path / "ca.pem", (5006, 5007), 1883, 1884), "utf-8")
    for variable in (USERNAME_ENV, PASSWORD_ENV, CA_FILE_ENV):
        monkeypatch.setenv(variable, "from-the-environment")
    served = load_config(path, where=Where.SERVED)
    assert [p.publish for p in served.profiles.values()] == [None, None]
    assert served.cells["line2"].publish is None
    assert served.cells["line2"].watch == ("pubA I 1", "pubB I 1")  # the target's own
    assert served.credentials() == Credentials()
    assert served.withheld == (
        *(("[mqtt]", key) for key in ("username", "password", "ca_file", "keepalive")),
        ("[target.pubA]", "publish"),
        ("[target.pubB]", "publish"),
        ("[cell.line2]", "publish"),
    )
    console = load_config(path, where=Where.CONSOLE)
    assert console.withheld == ()
    assert console.cells["line2"].publish == "mqtt://127.0.0.1:1884/cell"
    assert console.credentials().ca_file == "from-the-environment"


def test_the_notice_names_each_table_once_and_counts_past_a_few() -> None:
    assert withheld_notice(()) is None
    many = tuple((f"[target.t{n}]", "publish") for n in range(7))
    said = withheld_notice((("[mqtt]", "username"), ("[mqtt]", "ca_file"), *many))
    assert said == (
        "not read in a served console, which reaches its controller and nothing else: the "
        "config file's [mqtt] username, ca_file; [target.t0] publish; [target.t1] publish; "
        "[target.t2] publish; 4 more tables"
    )
    data = {"target": {"a\x1bb": {"host": "h", "publish": "x"}}, "mqtt": "not a table"}
    kept, withheld = withhold(data, lambda reach: reach is Reach.TARGET)
    assert withheld == (('[target."a\\x1bb"]', "publish"),)  # escaped as TOML quotes it
    assert kept == {"target": {"a\x1bb": {"host": "h"}}, "mqtt": "not a table"}
