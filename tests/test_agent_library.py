"""Scripts (``rac.connect``, ``rac.cell``) through the agent, judged at the fake
controller: the agent's one connection, its rules at its end, and a script that goes on
by itself when the agent goes away."""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

import rac_console as rac
from rac_console.agent.requests import GONE
from rac_console.agent.server import Agent
from rac_console.commands.target import Target
from tests.support.servers import Memory, RecordingServer


class Running:
    def __init__(self, target: Target) -> None:
        self.agent = Agent([("robot", target)], timeout=5.0, say=lambda text: None)
        self.agent.open()
        self.thread = threading.Thread(target=self.agent.serve, daemon=True)
        self.thread.start()

    def stop(self) -> None:
        self.agent.stop()
        self.thread.join(5)


@pytest.fixture
def controller(recording, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> RecordingServer:
    monkeypatch.setenv("RAC_CONSOLE_AGENT_DIR", str(tmp_path / "agent"))
    server: RecordingServer = recording(Memory())
    return server


@pytest.fixture
def running(controller: RecordingServer) -> Iterator[Running]:
    started = Running(Target("127.0.0.1", controller.port))
    yield started
    started.stop()


def test_two_scripts_share_the_agents_one_connection(
    running: Running, controller: RecordingServer
) -> None:
    address = f"127.0.0.1:{controller.port}"
    with rac.connect(address) as a, rac.connect(address) as b:
        assert a.via_agent and b.via_agent and "via agent" in repr(a)
        written = a.put("I", 9, 31)
        seen = b.get("I", 9)
        clients = [c["name"] for c in running.agent.status()["clients"]]
    assert (written.before, written.read_back, written.verified) == (9, 31, True)
    assert seen == 31
    assert len(clients) == 2 and all(name.startswith("script") for name in clients)
    assert controller.accepted == 1
    assert controller.lines.count(b"PUT:RC8:9:I:3,31") == 1


def test_direct_opens_a_session_of_its_own(running: Running, controller: RecordingServer) -> None:
    with rac.connect(f"127.0.0.1:{controller.port}", direct=True) as rc:
        assert not rc.via_agent
        assert rc.get("I", 1) == 1
    assert controller.accepted == 2  # the agent's, and the script's own


def test_the_agents_read_only_refuses_a_scripts_write_with_nothing_sent(
    controller: RecordingServer,
) -> None:
    held = Running(Target("127.0.0.1", controller.port, read_only=True, read_only_flag=True))
    try:
        with rac.connect(f"127.0.0.1:{controller.port}") as rc:
            assert rc.via_agent and rc.writes == "open"  # the script's own rules allow it
            with pytest.raises(rac.Refused, match=r"at the agent: .*read-only"):
                rc.put("I", 9, 31)
            assert rc.get("I", 9) == 9  # reads go on
    finally:
        held.stop()
    assert not [line for line in controller.lines if line.startswith(b"PUT")]


def test_a_script_goes_on_by_itself_when_the_agent_stops(
    controller: RecordingServer, caplog: pytest.LogCaptureFixture
) -> None:
    held = Running(Target("127.0.0.1", controller.port))
    address = f"127.0.0.1:{controller.port}"
    with rac.connect(address) as rc:
        rc.put("I", 4, 12)
        held.stop()
        with caplog.at_level(logging.WARNING, logger="rac_console"):
            assert rc.get("I", 4) == 12  # read again, over a session of its own
            rc.put("I", 4, 13)
        assert not rc.via_agent
    assert caplog.messages == [GONE.format(address=address)]
    assert controller.accepted == 2
    puts = [line for line in controller.lines if line.startswith(b"PUT")]
    assert puts == [b"PUT:RC8:4:I:3,12", b"PUT:RC8:4:I:3,13"]


def test_a_cells_members_go_through_the_agent_that_holds_them(
    running: Running, controller: RecordingServer
) -> None:
    with rac.cell([f"127.0.0.1:{controller.port}"]) as cell:
        (name,) = cell.names
        cell.run(f"@{name} put I 2 5")
    assert controller.accepted == 1
    assert controller.lines.count(b"PUT:RC8:2:I:3,5") == 1
