"""The agent and a client as a user runs them, on every platform the console ships for
(Linux's Unix socket; Windows' loopback port and token, in the Windows lane): one
connection at the controller, the agent killed and found again. Judged at the fake
controller."""

from __future__ import annotations

import json
import sys

from tests.support.drivers import Running, cli
from tests.support.servers import Memory, RecordingServer


def start_agent(env: dict[str, str], *args: str) -> Running:
    agent = Running(env, *args, "agent")
    agent.wait_for("the agent listening", lambda: any("listening on" in line for line in agent.out))
    return agent


def lines_of(stdout: str) -> list[str]:
    """``run``'s lines without their timings (the arrow as a Windows code page writes it)."""
    return [
        line.split("  S_OK")[0].split("   VT_")[0].replace("\u2192", "->")
        for line in stdout.splitlines()
    ]


def killed(agent: Running) -> None:
    """As a crash or Task Manager ends it: nothing of its own runs (no goodbye, its
    socket or port file left behind)."""
    agent.process.kill()
    agent.process.wait(20)


def test_commands_share_the_agents_connection_and_go_direct_once_it_is_killed(
    env: dict[str, str], recording
) -> None:
    controller: RecordingServer = recording(Memory())
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    agent = start_agent(env, *where)
    try:
        put = cli(env, *where, "put", "I", "5", "18", "--json")
        got = cli(env, *where, "get", "I", "5")
        status = json.loads(cli(env, "agent", "status", "--json").stdout)
    finally:
        killed(agent)
    assert put.returncode == 0, put.stderr
    assert "via agent" in put.stderr and "via agent" in got.stderr
    assert json.loads(put.stdout)["read_back"] == 18
    assert got.stdout.startswith("I5 = 18")
    assert [t["address"] for t in status["targets"]] == [f"127.0.0.1:{controller.port}"]
    assert controller.accepted == 1  # the agent's connection served both commands
    assert controller.lines.count(b"PUT:RC8:5:I:3,18") == 1

    # What the killed agent left behind counts as no agent: straight to the controller.
    alone = cli(env, *where, "get", "I", "5")
    assert alone.returncode == 0 and alone.stdout.startswith("I5 = 18")
    assert "via agent" not in alone.stderr and "Traceback" not in alone.stderr
    assert controller.accepted == 2
    assert cli(env, "agent", "status").returncode == 1

    again = start_agent(env, *where)  # takes the place of the one killed
    try:
        found = cli(env, *where, "get", "I", "5")
    finally:
        killed(again) if sys.platform == "win32" else again.stop()  # no Ctrl-C to send there
    assert "via agent" in found.stderr, (found.stderr, again.out, again.err)
    assert found.stdout.startswith("I5 = 18")
    assert controller.accepted == 3


def test_watch_and_run_go_through_the_agent_and_write_what_they_would_alone(
    env: dict[str, str], recording
) -> None:
    controller: RecordingServer = recording(Memory())
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    script = "put I 7 41\nget I 7\n"
    alone_run = cli(env, *where, "run", "-", stdin=script)
    alone_watch = cli(env, *where, "watch", "I", "7", "--count", "2", "--json")
    connections_alone = controller.accepted
    agent = start_agent(env, *where)
    try:
        run = cli(env, *where, "run", "-", stdin=script.replace("41", "42"))
        watched = cli(env, *where, "watch", "I", "7", "--count", "2", "--json")
    finally:
        killed(agent)
    assert run.returncode == alone_run.returncode == 0, run.stderr
    assert "via agent, as run" in run.stderr and "via agent" not in alone_run.stderr
    shown, before = lines_of(run.stdout), lines_of(alone_run.stdout)
    assert before == ["I7: 7 -> 41", "I7 = 41"]  # the lines as run alone shows them
    assert shown == ["I7: 41 -> 42", "I7 = 42"]
    assert watched.returncode == 0, watched.stderr
    assert "via agent, as watch" in watched.stderr
    rows = [json.loads(line) for line in watched.stdout.splitlines()]
    alone = [json.loads(line) for line in alone_watch.stdout.splitlines()]
    assert len(rows) == len(alone) == 2 and set(rows[0]) == set(alone[0])
    assert [row["values"]["I7"] for row in rows] == [42, 42]
    assert controller.accepted == connections_alone + 1  # the agent's, for both
    assert [line for line in controller.lines if line.startswith(b"PUT")] == [
        b"PUT:RC8:7:I:3,41",
        b"PUT:RC8:7:I:3,42",
    ]


def test_latency_is_measured_on_the_agents_connection(env: dict[str, str], recording) -> None:
    controller: RecordingServer = recording(Memory())
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    agent = start_agent(env, *where)
    try:
        measured = cli(env, *where, "latency", "5", "I", "3", "--json")
    finally:
        killed(agent)
    assert measured.returncode == 0, measured.stderr
    assert "via agent, as latency" in measured.stderr
    assert json.loads(measured.stdout)["count"] == 5
    assert controller.accepted == 1
    assert controller.lines.count(b"GET:RC8:3:I:") == 5
