"""The OPC UA server of ``watch --opcua`` as another implementation's client sees it:
node-opcua (``node-opcua-client@2`` from npm, installed here into ``.node-opcua/`` at the
repository's root once, under a file lock) driven by ``tests/opcua_node_client.js``,
against the real CLI as a subprocess on the built-in simulator, a simulator of its own
or a fake controller that records what reached the wire.

Skipped on Windows, without ``node`` and ``npm``, or when the install fails.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

import pytest

from tests.support.drivers import Running, cli
from tests.support.servers import Memory, RecordingServer
from tests.support.serving import start_sim

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent
INSTALL = ROOT / ".node-opcua"
PACKAGE = "node-opcua-client@2"
SCRIPT = Path(__file__).resolve().parent / "opcua_node_client.js"
#: How long the client script may take for all it does (it stops itself then), and how
#: long a test waits for a line or a process: only a hang reaches them.
CLIENT_DEADLINE = 30
DEADLINE = 20.0
NAMESPACE_URI = "urn:rac-console:watched"

WATCHED: tuple[str, ...] = ("I", "1", "F", "1", "D", "1", "S", "1", "IO", "128")
WATCHED += ("V", "1", "P", "1", "J", "1", "T", "1")
#: Each watched variable's OPC UA DataType and ValueRank, and for an array its length.
TYPES: dict[str, tuple[str, int, int | None]] = {
    "I1": ("Int32", -1, None),
    "F1": ("Float", -1, None),
    "D1": ("Double", -1, None),
    "S1": ("String", -1, None),
    "IO128": ("Boolean", -1, None),
    "V1": ("Float", 1, 3),
    "P1": ("Float", 1, 7),
    "J1": ("Float", 1, 8),
    "T1": ("Float", 1, 10),
}
#: AccessLevel's CurrentWrite bit.
CURRENT_WRITE = 0x02


# ------------------------------------------------------------------ node-opcua, installed


def _install() -> Path:
    """``node-opcua-client@2`` in ``.node-opcua/node_modules`` (installed by the first
    worker that gets the lock, reused after); pytest.skip when it cannot be."""
    if sys.platform == "win32":
        pytest.skip("the node-opcua client runs on POSIX here (a file lock of fcntl)")
    node, npm = shutil.which("node"), shutil.which("npm")
    if node is None or npm is None:
        pytest.skip("node and npm are needed for the node-opcua client")
    import fcntl

    modules = INSTALL / "node_modules"
    installed = modules / "node-opcua-client" / "package.json"
    INSTALL.mkdir(exist_ok=True)
    with open(INSTALL / "install.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if installed.exists():
            return modules
        environment = dict(os.environ) | {"npm_config_cache": str(INSTALL / ".npm-cache")}
        command = [npm, "install", "--no-audit", "--no-fund", "--prefix", str(INSTALL), PACKAGE]
        try:
            result = subprocess.run(
                command,
                cwd=INSTALL,
                env=environment,
                capture_output=True,
                text=True,
                timeout=300,
            )
        except subprocess.TimeoutExpired:
            pytest.skip(f"npm install {PACKAGE} did not end in 300 s")
        if result.returncode != 0 or not installed.exists():
            reason = npm_said(result.stderr + result.stdout)
            pytest.skip(f"npm install {PACKAGE} failed ({result.returncode}): {reason}")
    return modules


def npm_said(output: str) -> str:
    """npm's error in a line: its code and its last word (not where its log is)."""
    lines = [
        line.strip()
        for line in output.splitlines()
        if line.strip() not in ("", "npm error") and "complete log of this run" not in line
    ]
    code = next((line for line in lines if line.startswith("npm error code ")), None)
    said = [code] if code is not None else []
    if lines and lines[-1] != code:
        said.append(lines[-1])
    return "; ".join(said) or "no output"


@pytest.fixture(scope="module")
def node_opcua() -> Path:
    """Where node-opcua-client is (its ``node_modules``), for NODE_PATH."""
    return _install()


def client_env(env: dict[str, str], modules: Path) -> dict[str, str]:
    return env | {"NODE_PATH": str(modules)}


def parsed(stdout: str, stderr: str, code: int | None) -> dict[str, Any]:
    """The client script's one JSON object; its error shown when it failed."""
    lines = [line for line in stdout.splitlines() if line.strip()]
    assert code == 0 and len(lines) == 1, f"exit {code}\n{stdout}\n{stderr[-3000:]}"
    result: dict[str, Any] = json.loads(lines[0])
    return result


def node_client(
    env: dict[str, str], modules: Path, endpoint: str, **spec: object
) -> dict[str, Any]:
    """One run of the client script with ``spec`` (see the script), to its end."""
    spec.setdefault("deadline", CLIENT_DEADLINE)
    spec.setdefault("namespace", NAMESPACE_URI)
    result = subprocess.run(
        ["node", str(SCRIPT), endpoint, json.dumps(spec)],
        env=client_env(env, modules),
        capture_output=True,
        text=True,
        timeout=CLIENT_DEADLINE + 30,
    )
    return parsed(result.stdout, result.stderr, result.returncode)


# ------------------------------------------------------------------ the CLI, serving


def serve(env: dict[str, str], running: list[Running], *args: str) -> tuple[Running, str]:
    """``rac-console watch ARGS --opcua opc.tcp://127.0.0.1:0`` once it said where it
    serves, and polled once; it and its endpoint."""
    watch = Running(env, "watch", *args, "--opcua", "opc.tcp://127.0.0.1:0")
    running.append(watch)
    said = re.compile(r"serving the watched values over OPC UA at (opc\.tcp://\S+) \((.+)\)$")
    watch.wait_for("the OPC UA endpoint", lambda: any(said.search(line) for line in watch.err))
    watch.wait_for("a first poll", lambda: bool(watch.out))
    match = next(m for line in watch.err if (m := said.search(line)))
    return watch, match.group(1)


def printed_values(lines: list[str]) -> dict[str, list[object]]:
    """What each of the watch's lines said of each variable (``NAME=TEXT``, tab
    separated after the time), as values of OPC UA's types."""
    values: dict[str, list[object]] = {}
    for line in lines:
        for field in line.split("\t")[1:]:
            name, _, text = field.partition("=")
            kind = re.sub(r"\d+$", "", name)
            value: object
            if kind == "I":
                value = int(text)
            elif kind in ("F", "D"):
                value = float(text)
            elif kind == "IO":
                value = {"ON": True, "OFF": False}[text]
            elif kind in ("V", "P", "J", "T"):
                value = [float(item) for item in text.split(",")]
            else:
                value = text
            values.setdefault(name, []).append(value)
    return values


def same(served: object, printed: object) -> bool:
    """A value served as a Float (32 bits) is the one printed, to a Float's precision."""
    if isinstance(printed, list):
        return isinstance(served, list) and served == pytest.approx(printed, rel=1e-6)
    if isinstance(printed, float):
        return served == pytest.approx(printed, rel=1e-6)
    return served == printed and type(served) is type(printed)


def when(text: str) -> datetime:
    return datetime.fromisoformat(text.replace("Z", "+00:00"))


def wait(holds: Callable[[], bool], what: str, deadline: float = DEADLINE) -> None:
    end = time.monotonic() + deadline
    while not holds():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {deadline} s waiting for {what}")
        time.sleep(0.05)


@pytest.fixture
def memory(recording: Callable[..., RecordingServer]) -> Iterator[RecordingServer]:
    """A fake controller keeping what is put (``Memory``), recording the wire."""
    yield recording(Memory())


# ------------------------------------------------------------------ browse and read


def test_node_opcua_browses_the_watched_variables_with_their_types_and_reads_them_good(
    env: dict[str, str], running: list[Running], node_opcua: Path
) -> None:
    watch, endpoint = serve(env, running, *WATCHED)
    assert any(line.endswith("(read-only)") for line in watch.err), watch.err
    result = node_client(env, node_opcua, endpoint, target="sim", read=list(TYPES))
    now = datetime.now(UTC)
    ns = result["namespaceIndex"]
    assert ns > 0
    assert result["folders"] == ["sim"]
    browsed = {entry["name"]: entry for entry in result["browse"]}
    assert set(browsed) == set(TYPES)
    for name, (data_type, value_rank, length) in TYPES.items():
        entry, read = browsed[name], result["read"][name]
        assert entry["namespaceIndex"] == ns and entry["nodeId"] == f"ns={ns};s=sim/{name}"
        assert entry["nodeClass"] == "Variable"
        assert (entry["dataType"], entry["valueRank"]) == (data_type, value_rank), entry
        assert entry["properties"] == ["Status"] and entry["status"] == "OK", entry
        assert entry["accessLevel"] & CURRENT_WRITE == 0, entry  # read-only
        assert read["statusCode"] == "Good", (name, read)
        assert read["variantType"] == data_type, (name, read)
        if length is None:
            assert read["arrayType"] == "Scalar", (name, read)
        else:
            assert read["arrayType"] == "Array" and len(read["value"]) == length, (name, read)
        source = when(read["sourceTimestamp"])
        assert now - timedelta(minutes=1) <= source <= now, (name, read, now)
    # The values are the ones the watch printed (the simulator's own).
    watch.wait_for("a line after the reads", lambda: len(watch.out) >= 2)
    printed = printed_values(watch.out)
    assert set(printed) == set(TYPES)
    for name in TYPES:
        served = result["read"][name]["value"]
        assert any(same(served, value) for value in printed[name]), (name, served, printed[name])
    assert result["read"]["I1"]["value"] == 1
    assert result["read"]["S1"]["value"] == "RC8 simulator"
    assert result["read"]["IO128"]["value"] is True
    assert result["read"]["P1"]["value"] == [350, 0, 450, 180, 0, 180, 5]


# ------------------------------------------------------------------ a subscription


def test_a_node_opcua_subscription_sees_a_value_changed_in_the_controller(
    env: dict[str, str], running: list[Running], node_opcua: Path
) -> None:
    port = start_sim(env, running)
    _, endpoint = serve(env, running, "I", "1", "-H", "127.0.0.1", "-p", str(port))
    spec = {
        "read": ["I1"],
        "subscribe": {"node": "I1", "interval": 100, "until": 77},
        "deadline": CLIENT_DEADLINE,
        "namespace": NAMESPACE_URI,
    }
    client = Running(
        client_env(env, node_opcua), endpoint, json.dumps(spec), program=("node", str(SCRIPT))
    )
    running.append(client)
    client.wait_for("the subscription's first notification", lambda: "subscribed" in client.err)
    put = cli(env, "put", "I", "1", "77", "-H", "127.0.0.1", "-p", str(port), "--direct")
    assert put.returncode == 0, put.stderr
    code = client.process.wait(CLIENT_DEADLINE + 10)
    client.wait_for("the client's output", lambda: bool(client.out))
    result = parsed("\n".join(client.out), "\n".join(client.err), code)
    assert result["target"] == f"127.0.0.1:{port}"
    subscription = result["subscription"]
    notifications = subscription["notifications"]
    assert subscription["reached"], notifications
    first, last = notifications[0], notifications[-1]
    assert (first["value"], first["statusCode"]) == (1, "Good"), notifications
    assert (last["value"], last["statusCode"], last["variantType"]) == (77, "Good", "Int32")
    assert when(last["sourceTimestamp"]) > when(first["sourceTimestamp"]), notifications


# ------------------------------------------------------------------ writes


def test_a_node_opcua_write_is_refused_without_opcua_writes_and_sends_nothing(
    env: dict[str, str], running: list[Running], node_opcua: Path, memory: RecordingServer
) -> None:
    watch, endpoint = serve(env, running, "I", "1", *memory.args)
    assert any(line.endswith("(read-only)") for line in watch.err), watch.err
    result = node_client(
        env,
        node_opcua,
        endpoint,
        read=["I1"],
        write={"node": "I1", "dataType": "Int32", "value": 42},
    )
    assert result["read"]["I1"]["statusCode"] == "Good"
    assert result["write"]["statusCode"] in ("BadNotWritable", "BadUserAccessDenied"), result
    (browsed,) = result["browse"]
    assert browsed["accessLevel"] & CURRENT_WRITE == 0, browsed
    # A poll after the write has been answered: anything the write set going would be
    # on the wire before it.
    gets = sum(line.startswith(b"GET") for line in memory.lines)
    wait(lambda: sum(line.startswith(b"GET") for line in memory.lines) > gets, "another poll")
    assert not [line for line in memory.lines if line.startswith(b"PUT")], memory.lines


def test_a_node_opcua_write_with_opcua_writes_reaches_the_controller_and_answers_good(
    env: dict[str, str], running: list[Running], node_opcua: Path, memory: RecordingServer
) -> None:
    watch, endpoint = serve(env, running, "I", "1", *memory.args, "--opcua-writes")
    assert any(line.endswith("(writes through the write gate)") for line in watch.err)
    result = node_client(
        env,
        node_opcua,
        endpoint,
        read=["I1"],
        write={"node": "I1", "dataType": "Int32", "value": 42},
        subscribe={"node": "I1", "interval": 100, "until": 42},
    )
    (browsed,) = result["browse"]
    assert browsed["accessLevel"] & CURRENT_WRITE, browsed
    assert result["write"]["statusCode"] == "Good", (result, watch.err)
    # Good comes once read back, so the PUT is on the wire already; one PUT only.
    wait(lambda: b"PUT:RC8:1:I:3,42" in memory.lines, "the PUT", deadline=5)
    puts = [line for line in memory.lines if line.startswith(b"PUT")]
    assert puts == [b"PUT:RC8:1:I:3,42"], memory.lines
    # And the served value follows.
    subscription = result["subscription"]
    assert subscription["reached"], subscription
    assert subscription["notifications"][-1]["statusCode"] == "Good"
