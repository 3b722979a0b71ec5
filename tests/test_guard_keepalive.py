"""An idle console learns that its link died (issue 19, item 5): TCP keepalive, over a
real network path. The simulator runs in a network namespace joined to this one by a
veth pair; the cable is pulled by dropping every packet there. Skipped where
namespaces cannot be made (not root, no ``ip`` or ``iptables``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass

import pytest

from rac_console.commands.outcome import Outcome
from rac_console.engine import Engine
from tests.support.drivers import Front

pytestmark = pytest.mark.slow

#: Keepalive gives up after 5 + 2 x 3 = 11 s; the engine looks every second.
NOTICE_WITHIN = 40.0


@dataclass
class Link:
    namespace: str
    address: str
    port: int

    def pull(self) -> None:
        for chain in ("INPUT", "OUTPUT"):
            _ip_netns("iptables", "-A", chain, "-j", "DROP", namespace=self.namespace)

    def restore(self) -> None:
        _ip_netns("iptables", "-F", namespace=self.namespace)


def _ip_netns(*words: str, namespace: str) -> None:
    subprocess.run(["ip", "netns", "exec", namespace, *words], check=True, timeout=20)


def _namespaces_unavailable() -> str | None:
    if sys.platform != "linux" or os.geteuid() != 0:
        return "needs root on Linux"
    for tool in ("ip", "iptables"):
        if shutil.which(tool) is None:
            return f"needs {tool}"
    return None


def _own_addresses() -> tuple[str, str]:
    """This end and the namespace's end of a /30 of this process's own in 198.18.0.0/15
    (set aside for network tests): two pytest-xdist workers, or two runs of the suite at
    once, never put one subnet on two links (the root namespace would route one test's
    packets into the other's namespace). Picked from the PID, passing over a block whose
    address some other process has already put on a link here."""
    used = subprocess.run(
        ["ip", "-o", "-4", "addr", "show"], capture_output=True, text=True, timeout=20
    ).stdout
    for step in range(32768):
        block = (os.getpid() + step) % 32768 * 4
        here, there = (
            f"198.{18 + block // 65536}.{block // 256 % 256}.{block % 256 + end}" for end in (1, 2)
        )
        if f" {here}/" not in used:
            return here, there
    raise AssertionError("no free /30 in 198.18.0.0/15")


@pytest.fixture
def link() -> Iterator[Link]:
    why = _namespaces_unavailable()
    if why:
        pytest.skip(f"network namespaces: {why}")
    tag = str(os.getpid())  # unique among running processes: names no worker shares
    namespace, here, there = f"rka{tag}", f"rkh{tag}", f"rkt{tag}"
    here_address, there_address = _own_addresses()
    made = subprocess.run(["ip", "netns", "add", namespace], capture_output=True, timeout=20)
    if made.returncode:
        pytest.skip(f"network namespaces: ip netns add failed: {made.stderr.decode().strip()}")
    simulator: subprocess.Popen[bytes] | None = None
    try:
        for words in (
            ["ip", "link", "add", here, "type", "veth", "peer", "name", there],
            ["ip", "link", "set", there, "netns", namespace],
            ["ip", "addr", "add", f"{here_address}/30", "dev", here],
            ["ip", "link", "set", here, "up"],
        ):
            subprocess.run(words, check=True, timeout=20)
        _ip_netns("ip", "addr", "add", f"{there_address}/30", "dev", there, namespace=namespace)
        _ip_netns("ip", "link", "set", there, "up", namespace=namespace)
        _ip_netns("ip", "link", "set", "lo", "up", namespace=namespace)
        simulator = subprocess.Popen(
            [
                "ip",
                "netns",
                "exec",
                namespace,
                sys.executable,
                "-m",
                "rac_console",
                "sim",
                "--bind",
                there_address,
                "--port",
                "5006",
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        _wait_listening(namespace, simulator, there_address)
        yield Link(namespace, there_address, 5006)
    finally:
        if simulator is not None:
            simulator.kill()
            simulator.wait(20)
        subprocess.run(["ip", "netns", "del", namespace], capture_output=True, timeout=20)
        subprocess.run(["ip", "link", "del", here], capture_output=True, timeout=20)


def _wait_listening(namespace: str, simulator: subprocess.Popen[bytes], address: str) -> None:
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        assert simulator.poll() is None, simulator.stderr.read() if simulator.stderr else ""
        listening = subprocess.run(
            ["ip", "netns", "exec", namespace, "ss", "-ltn"], capture_output=True, timeout=20
        )
        if f"{address}:5006".encode() in listening.stdout:
            return
        time.sleep(0.05)
    raise AssertionError("the simulator did not listen within 20 s")


def test_an_idle_console_shows_a_pulled_cable(link: Link) -> None:
    engine = Engine(link.address, link.port, interval=0.2, timeout=2.0)
    engine.start()
    try:
        front = Front(engine)
        front.run("get I 1")
        front.until(
            lambda: front.status is not None and front.status.connection == "connected",
            "connected",
        )
        link.pull()
        deadline = time.monotonic() + NOTICE_WITHIN
        while not (front.status is not None and front.status.connection == "lost"):
            assert time.monotonic() < deadline, "an idle connection over a pulled cable"
            time.sleep(0.1)
            front.drain()
        assert any("connection lost while idle" in alert for alert in front.alerts), front.alerts
        link.restore()
        seq = engine.submit("get I 1")  # the first command after the outage gets through
        front.until(lambda: seq in front.results, "the get after the restore")
        [outcome] = front.results[seq].feedback
        assert isinstance(outcome, Outcome) and outcome.ok, outcome
    finally:
        engine.stop()


def test_a_reconnect_over_a_pulled_cable_is_never_shown_as_connected(link: Link) -> None:
    """A poll times out and the session is reset; the connect that follows blocks for a
    whole timeout: meanwhile the status line says connecting, not connected."""
    engine = Engine(link.address, link.port, interval=0.2, timeout=1.0)
    engine.start()
    try:
        front = Front(engine)
        front.run("watch I 1")
        front.until(lambda: "I1" in front.rows and front.rows["I1"].status == "OK", "a polled row")
        link.pull()
        front.until(
            lambda: front.status is not None and front.status.connection == "connecting",
            "connecting… on the status line while the connect blocks",
        )
        link.restore()
    finally:
        engine.stop()
