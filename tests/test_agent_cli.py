"""``rac-console agent`` and ``agent status`` as a user runs them, and a console that
goes through the agent, judged from the controller's side."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.drivers import Running, cli, one_error_line
from tests.support.servers import Memory, RecordingServer

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(sys.platform == "win32", reason="the Unix socket's tests"),
]


def agent_socket(env: dict[str, str]) -> Path:
    return Path(env["XDG_RUNTIME_DIR"]) / "rac-console" / "agent.sock"


def start_agent(env: dict[str, str], *args: str) -> Running:
    agent = Running(env, *args, "agent")
    agent.wait_for("the agent listening", lambda: any("listening on" in line for line in agent.out))
    return agent


def test_the_agent_holds_its_target_says_so_and_leaves_nothing_behind(
    env: dict[str, str], recording
) -> None:
    controller: RecordingServer = recording(Memory())
    agent = start_agent(env, "-H", "127.0.0.1", "-p", str(controller.port))
    try:
        path = agent_socket(env)
        assert oct(path.stat().st_mode & 0o777) == "0o600"
        assert oct(path.parent.stat().st_mode & 0o777) == "0o700"
        status = json.loads(cli(env, "agent", "status", "--json").stdout)
        assert status["running"] is True
        (target,) = status["targets"]
        assert target["address"] == f"127.0.0.1:{controller.port}"
        assert target["state"] == "connected"
        again = cli(env, "-H", "127.0.0.1", "-p", str(controller.port), "agent")
        assert again.returncode == 2
        assert "an agent is already running" in one_error_line(again)
        agent.process.send_signal(signal.SIGTERM)
        assert agent.process.wait(20) == 0
    finally:
        agent.stop()
    assert not agent_socket(env).exists()
    gone = cli(env, "agent", "status")
    assert gone.returncode == 1
    assert "no agent is running" in gone.stderr
    assert controller.accepted == 1  # the agent's one connection, and nothing after it


def test_a_socket_left_by_a_dead_agent_is_no_agent(env: dict[str, str]) -> None:
    path = agent_socket(env)
    path.parent.mkdir(mode=0o700)
    left = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    left.bind(str(path))
    left.close()  # as an agent killed with SIGKILL leaves it: a file nobody listens on
    status = cli(env, "agent", "status")
    assert status.returncode == 1
    agent = start_agent(env)  # takes its place
    try:
        assert json.loads(cli(env, "agent", "status", "--json").stdout)["running"] is True
    finally:
        agent.stop()


def test_a_console_goes_through_the_agent_and_says_so(
    env: dict[str, str], recording, terminal
) -> None:
    controller: RecordingServer = recording(Memory())
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    agent = start_agent(env, *where)
    try:
        runtime = env["XDG_RUNTIME_DIR"]
        command = f"env XDG_RUNTIME_DIR={runtime} {sys.executable} -m rac_console {' '.join(where)}"
        terminal.tmux("new-session", "-d", "-s", "t", "-x", "100", "-y", "30", command)
        terminal.until("via agent")
        terminal.tmux("send-keys", "-t", "t", "put I 5 17", "Enter")
        terminal.until("read back 17")
        status = json.loads(cli(env, "agent", "status", "--json").stdout)
        assert [c["target"] for c in status["clients"]] == [f"127.0.0.1:{controller.port}"]
        assert controller.accepted == 1  # the agent's, which the console used
        assert controller.lines.count(b"PUT:RC8:5:I:3,17") == 1
    finally:
        agent.stop()
    terminal.until("the agent stopped: going on with a session of our own")
    terminal.tmux("send-keys", "-t", "t", "get I 5", "Enter")
    terminal.until("I5 = 17")
    assert controller.accepted == 2  # its own, once the agent was gone


def test_a_one_shot_command_goes_through_the_agent_and_prints_what_it_would_alone(
    env: dict[str, str], recording
) -> None:
    controller: RecordingServer = recording(Memory())
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    alone = cli(env, *where, "put", "I", "5", "17", "--json")
    agent = start_agent(env, *where)
    try:
        via = cli(env, *where, "put", "I", "5", "18", "--json")
        read = cli(env, *where, "get", "I", "5")
        direct = cli(env, *where, "get", "I", "5", "--direct")
        accepted_with_agent = controller.accepted
    finally:
        agent.stop()
    assert via.returncode == alone.returncode == 0
    assert "via agent" in via.stderr and "via agent" not in alone.stderr
    shown, before = json.loads(via.stdout), json.loads(alone.stdout)
    assert set(shown) == set(before)  # the same fields, the same meaning
    assert (shown["read_back"], shown["verified"]) == (18, True)
    assert read.stdout.startswith("I5 = 18") and "via agent" in read.stderr
    assert "via agent" not in direct.stderr
    # alone: one; the agent: one for every command through it; --direct: one of its own
    assert accepted_with_agent == 3
    puts = [line for line in controller.lines if line.startswith(b"PUT")]
    assert puts == [b"PUT:RC8:5:I:3,17", b"PUT:RC8:5:I:3,18"]


def test_a_write_to_the_agents_simulator_stays_for_the_next_command(env: dict[str, str]) -> None:
    agent = start_agent(env)
    try:
        put = cli(env, "put", "I", "1", "55")
        get = cli(env, "get", "I", "1")
    finally:
        agent.stop()
    assert put.returncode == 0 and "the write is gone" not in put.stderr
    assert get.stdout.startswith("I1 = 55"), get.stdout


def test_without_a_runtime_folder_nothing_unmeant_is_said(env: dict[str, str]) -> None:
    bare = {k: v for k, v in env.items() if k != "XDG_RUNTIME_DIR"}
    result = cli(bare, "get", "I", "1", "--direct")
    assert result.returncode == 0
    assert "Warning" not in result.stderr and "Traceback" not in result.stderr
    status = cli(bare, "agent", "status")
    assert "Warning" not in status.stderr and "Traceback" not in status.stderr


def _as_nobody() -> list[str]:
    """A command prefix that runs as another user, or a skip where that cannot be."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("setpriv") is None:
        pytest.skip("needs root and setpriv to run a client as another user")
    return ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"]


def _their_env(env: dict[str, str], base: Path) -> dict[str, str]:
    """The other user's home and folders, where they may write."""
    home = base / "home"
    home.mkdir(exist_ok=True)
    home.chmod(0o777)
    places = ("XDG_CONFIG_HOME", "XDG_STATE_HOME", "XDG_CACHE_HOME", "XDG_DATA_HOME")
    return env | {"HOME": str(home)} | {name: str(home / name) for name in places}


@pytest.fixture
def open_folder() -> Iterator[Path]:
    """A folder another user can walk to (the test's own tmp_path is root's alone)."""
    base = Path(tempfile.mkdtemp(prefix="rac-agent-"))
    base.chmod(0o755)
    yield base
    shutil.rmtree(base, ignore_errors=True)


def test_another_user_finds_no_agent(env: dict[str, str], open_folder: Path) -> None:
    prefix = _as_nobody()
    folder = open_folder / "agent"
    env = env | {"RAC_CONSOLE_AGENT_DIR": str(folder)}
    agent = start_agent(env)
    try:
        theirs = _their_env(env, open_folder)
        status = subprocess.run(
            [*prefix, sys.executable, "-m", "rac_console", "agent", "status"],
            env=theirs, capture_output=True, text=True, timeout=60,
        )  # fmt: skip
        assert status.returncode == 1, status.stderr
        assert "no agent is running" in status.stderr
        assert "Traceback" not in status.stderr
    finally:
        agent.stop()
    assert not any("attached" in line for line in agent.out)


def test_the_agent_turns_away_another_user_even_through_an_open_socket(
    env: dict[str, str], open_folder: Path
) -> None:
    prefix = _as_nobody()
    folder = open_folder / "agent"
    env = env | {"RAC_CONSOLE_AGENT_DIR": str(folder)}
    agent = start_agent(env)
    try:
        folder.chmod(0o755)  # as a mistake would leave them
        (folder / "agent.sock").chmod(0o666)
        probe = (
            "import socket, sys\n"
            "from rac_console.agent.wire import Channel, PROTOCOL, RELEASE\n"
            "s = socket.socket(socket.AF_UNIX)\n"
            f"s.connect({str(folder / 'agent.sock')!r})\n"
            "c = Channel(s)\n"
            "try:\n"
            "    hello = {'op': 'hello', 'protocol': PROTOCOL, 'release': RELEASE}\n"
            "    c.send(hello | {'want': 'status'})\n"
            "    print('ANSWER', c.receive())\n"
            "except Exception as e:\n"
            "    print('CLOSED', type(e).__name__)\n"
        )
        result = subprocess.run(
            [*prefix, sys.executable, "-c", probe],
            env=_their_env(env, open_folder), capture_output=True, text=True, timeout=60,
            cwd=str(Path(__file__).parent.parent),
        )  # fmt: skip
    finally:
        agent.stop()
    assert result.stdout.startswith("CLOSED"), result.stdout + result.stderr


def test_check_names_the_agent_that_holds_the_controller(env: dict[str, str], recording) -> None:
    controller: RecordingServer = recording(Memory())
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    before = cli(env, *where, "check")
    agent = start_agent(env, *where)
    try:
        during = cli(env, *where, "check")
    finally:
        agent.stop()
    assert "holds this controller" not in before.stderr
    assert "the agent (pid " in during.stderr and "holds this controller" in during.stderr
    assert during.returncode == before.returncode == 0  # the check itself as before


def test_the_agents_own_feed_serves_its_watch_list_whoever_is_attached(
    env: dict[str, str], recording, tmp_path: Path
) -> None:
    import re
    import time
    import urllib.request

    controller: RecordingServer = recording(Memory())
    rows = tmp_path / "plant.toml"
    rows.write_text('[[watch]]\ntype = "I"\nindex = 3\nlabel = "parts"\n', encoding="utf-8")
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    agent = Running(env, *where, "agent", "--watch", str(rows), "--metrics", "127.0.0.1:0")
    try:
        agent.wait_for("the agent listening", lambda: any("listening on" in s for s in agent.out))
        served = next(m for line in agent.out if (m := re.search(r"http://\S+/metrics", line)))
        deadline = time.monotonic() + 20
        page = ""
        while 'variable="I3"' not in page or "rac_value" not in page:
            assert time.monotonic() < deadline, page
            with urllib.request.urlopen(served.group(0), timeout=5) as reply:
                page = reply.read().decode()
            time.sleep(0.1)
        put = cli(env, *where, "put", "I", "3", "77")
        while not re.search(r'rac_value\{[^}]*variable="I3"[^}]*\} 77', page):
            assert time.monotonic() < deadline + 20, page
            with urllib.request.urlopen(served.group(0), timeout=5) as reply:
                page = reply.read().decode()
            time.sleep(0.1)
        status = json.loads(cli(env, "agent", "status", "--json").stdout)
    finally:
        agent.stop()
    assert "via agent" in put.stderr
    assert status["exporters"] == [{"target": f"127.0.0.1:{controller.port}", "rows": 1}]
    assert controller.accepted == 1  # the feed's polls and the put: the agent's connection


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (("--mqtt", "mqtt://127.0.0.1/cell"), "give it with --watch FILE"),
        (("--watch", "WATCH"), "give --mqtt, --metrics, --opcua or --log-csv with it"),
    ],
)
def test_an_agent_feed_with_nothing_to_feed_is_refused_in_one_line(
    env: dict[str, str], tmp_path: Path, args: tuple[str, ...], says: str
) -> None:
    rows = tmp_path / "rows.toml"
    rows.write_text('[[watch]]\ntype = "I"\nindex = 3\n', encoding="utf-8")
    given = [str(rows) if arg == "WATCH" else arg for arg in args]
    refused = cli(env, "agent", *given)
    assert refused.returncode == 2
    assert says in one_error_line(refused)
    assert not agent_socket(env).exists()


def test_the_agent_keeps_one_frame_log_of_every_client_naming_who_asked(
    env: dict[str, str], recording, tmp_path: Path
) -> None:
    controller: RecordingServer = recording(Memory())
    record, transcript = tmp_path / "agent.jsonl", tmp_path / "agent.log"
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    agent = start_agent(env, *where, "--record", str(record), "--log", str(transcript))
    try:
        put = cli(env, *where, "put", "I", "8", "21")
        got = cli(env, *where, "get", "I", "8")
    finally:
        agent.stop()
    assert "via agent, as command 1" in put.stderr and "via agent, as command 2" in got.stderr
    lines = [json.loads(line) for line in record.read_text(encoding="utf-8").splitlines()]
    sent = [(line["client"], line["text"]) for line in lines if line["dir"] == "tx"]
    assert ("command 1", "PUT:RC8:8:I:3,21") in sent
    assert ("command 2", "GET:RC8:8:I:") in sent
    said = transcript.read_text(encoding="utf-8")
    assert "PUT:RC8:8:I:3,21   [command 1]" in said


def test_a_clients_name_for_itself_is_a_plain_word_in_the_others_logs() -> None:
    from rac_console.agent.hellos import client_kind

    assert client_kind("REPL") == "REPL" and client_kind("served console") == "served console"
    for hostile in ("\x1b[2Jx", "a" * 40, "", None, "x\ny", "robot[1]"):
        assert client_kind(hostile) == "client"


def test_an_agent_feed_whose_csv_log_cannot_be_written_is_one_line_and_leaves_nothing(
    env: dict[str, str], tmp_path: Path
) -> None:
    rows = tmp_path / "rows.toml"
    rows.write_text('[[watch]]\ntype = "I"\nindex = 3\n', encoding="utf-8")
    csv = tmp_path / "no such folder" / "x.csv"
    refused = cli(env, "agent", "--watch", str(rows), "--log-csv", str(csv), timeout=60)
    assert refused.returncode == 2
    assert "cannot write the CSV log" in one_error_line(refused)
    assert not agent_socket(env).exists()


def test_an_agent_folder_that_is_a_file_is_said_so(env: dict[str, str], tmp_path: Path) -> None:
    taken = tmp_path / "a file"
    taken.write_text("", encoding="utf-8")
    refused = cli(env | {"RAC_CONSOLE_AGENT_DIR": str(taken)}, "agent")
    assert refused.returncode == 2
    assert "is a file, not a folder" in one_error_line(refused)
