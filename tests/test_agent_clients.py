"""Front ends through the agent, judged from the controller's side: one connection for
every client, each client's own rules at the gate, and a client that goes on alone when
the agent goes away."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.agent.client import AGENT_GONE, RemoteEngine, attach
from rac_console.agent.server import Agent
from rac_console.commands.policy import TargetProfile, WritePolicy, Writes
from rac_console.commands.target import Target
from rac_console.engine import ConfirmWrite, EngineOptions
from rac_console.engine.setup.where import Where
from tests.support.drivers import Front
from tests.support.servers import Memory, RecordingServer


@pytest.fixture
def agent_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    folder = tmp_path / "agent"
    monkeypatch.setenv("RAC_CONSOLE_AGENT_DIR", str(folder))
    return folder


class Running:
    def __init__(self, server: RecordingServer, target: Target | None = None) -> None:
        self.target = target or Target("127.0.0.1", server.port)
        self.said: list[str] = []
        self.agent = Agent([("robot", self.target)], timeout=5.0, say=self.said.append)
        self.agent.open()
        self.thread = threading.Thread(target=self.agent.serve, daemon=True)
        self.thread.start()

    def stop(self) -> None:
        self.agent.stop()
        self.thread.join(5)


@pytest.fixture
def controller(recording) -> RecordingServer:
    server: RecordingServer = recording(Memory())
    return server


@pytest.fixture
def running(agent_dir: Path, controller: RecordingServer) -> Iterator[Running]:
    started = Running(controller)
    yield started
    started.stop()


def client(target: Target, *, read_only: bool = False) -> Front:
    rules = Target(target.host, target.port, read_only=read_only, read_only_flag=read_only)
    engine = attach(
        rules, EngineOptions(timeout=5.0, interval=0.05), client="test", where=Where.CONSOLE
    )
    assert isinstance(engine, RemoteEngine)
    engine.start()
    return Front(engine)  # type: ignore[arg-type]


def test_two_clients_share_one_connection_and_each_sees_the_other_write(
    running: Running, controller: RecordingServer
) -> None:
    a, b = client(running.target), client(running.target)
    try:
        a.run("watch I 7")
        assert b.outcome("put I 7 42").verified
        a.until(
            lambda: a.rows["I7"].variant is not None and a.rows["I7"].variant.value == 42, "42 at a"
        )
        a.engine.set_poll_frames(False)
        a.until(
            lambda: any(f.source == "test 2" and f.data.startswith(b"PUT") for f in a.frames),
            "b's PUT in a's log",
        )
    finally:
        a.engine.stop()
        b.engine.stop()
    assert controller.accepted == 1
    assert controller.lines.count(b"PUT:RC8:7:I:3,42") == 1


def test_a_read_only_client_is_refused_at_the_agents_gate(
    running: Running, controller: RecordingServer
) -> None:
    a = client(running.target, read_only=True)
    try:
        outcome = a.outcome("put I 7 42")
    finally:
        a.engine.stop()
    assert outcome.status.name == "REFUSED", outcome
    assert not any(line.startswith(b"PUT") for line in controller.lines)


def test_no_agent_means_no_attach(agent_dir: Path, controller: RecordingServer) -> None:
    target = Target("127.0.0.1", controller.port)
    assert attach(target, EngineOptions(), client="test", where=Where.CONSOLE) is None
    assert controller.accepted == 0


def test_a_client_goes_on_alone_when_the_agent_stops(
    running: Running, controller: RecordingServer
) -> None:
    a = client(running.target)
    try:
        a.run("watch I 9")
        running.stop()
        a.until(lambda: any("the agent stopped" in text for text in a.alerts), "the one line")
        seen = len(controller.lines)
        a.until(
            lambda: controller.accepted == 2 and len(controller.lines) > seen + 2,
            "polls of its own",
        )
        assert a.run("get I 9")
    finally:
        a.engine.stop()
    assert AGENT_GONE.split(":")[0] in " ".join(a.alerts)


def test_writes_reach_the_controller_in_the_order_the_agent_received_them(
    agent_dir: Path, recording
) -> None:
    """a's put arrives first while a's engine waits on a slow GET; b's put arrives
    next, b's engine idle: a's PUT still reaches the controller first."""
    release = threading.Event()
    controller: RecordingServer = recording(Memory(hold=(b"GET:RC8:1:I:", release)))
    running = Running(controller)
    a, b = client(running.target), client(running.target)
    try:
        a.engine.submit("get I 1")  # held by the controller until released
        put_a = a.engine.submit("put I 2 5")
        a.until(lambda: _lines_received(running, "test 1") == 2, "a's two lines at the agent")
        put_b = b.engine.submit("put I 3 6")
        b.until(lambda: _lines_received(running, "test 2") == 1, "b's line at the agent")
        b.until(
            lambda: any("waits for test 1's earlier write" in said for said in b.alerts),
            "b told why its write waits",
        )
        release.set()
        a.until(lambda: put_a in a.results, "a's put answered")
        b.until(lambda: put_b in b.results, "b's put answered")
    finally:
        release.set()
        a.engine.stop()
        b.engine.stop()
        running.stop()
    puts = [line for line in controller.lines if line.startswith(b"PUT")]
    assert puts == [b"PUT:RC8:2:I:3,5", b"PUT:RC8:3:I:3,6"]


def _lines_received(running: Running, name: str) -> int:
    return next((c.lines for c in running.agent.clients.values() if c.name == name), 0)


class Answering(Front):
    """A front end that answers each write's question as told."""

    def __init__(self, engine: object, yes: bool) -> None:
        super().__init__(engine)  # type: ignore[arg-type]
        self.yes = yes
        self.asked: list[str] = []

    def take_confirm(self, target: str | None, question: ConfirmWrite) -> None:
        self.asked.append(question.request)
        self.engine.answer_confirm(question.seq, self.yes)


@pytest.mark.parametrize("yes", [False, True], ids=["no", "yes"])
def test_a_confirm_targets_question_is_asked_at_the_client(
    agent_dir: Path, controller: RecordingServer, yes: bool
) -> None:
    policy = WritePolicy(Writes.CONFIRM, None, "profile cell3")
    profile = TargetProfile("cell3", "127.0.0.1", controller.port, "Cell 3", "red", policy)
    held = Target("127.0.0.1", controller.port, profile, policy)
    running = Running(controller, held)
    engine = attach(
        Target("127.0.0.1", controller.port),
        EngineOptions(timeout=5.0, interval=0.05),
        client="test",
        where=Where.CONSOLE,
    )
    assert isinstance(engine, RemoteEngine)
    engine.start()
    front = Answering(engine, yes)
    try:
        seq = engine.submit("put I 4 9")
        front.until(lambda: seq in front.results, "the put's answer")
    finally:
        engine.stop()
        running.stop()
    assert front.asked == ["PUT:RC8:4:I:3,9"]
    puts = [line for line in controller.lines if line.startswith(b"PUT")]
    assert puts == ([b"PUT:RC8:4:I:3,9"] if yes else [])


def test_a_client_that_goes_away_leaves_no_watch_behind(
    running: Running, controller: RecordingServer
) -> None:
    from rac_console.agent import endpoint
    from rac_console.agent.wire import PROTOCOL, RELEASE, Channel

    reached = endpoint.reach()
    assert reached is not None
    gone = Channel(reached[0])  # a client killed: it says no goodbye
    gone.send(
        {"op": "hello", "protocol": PROTOCOL, "release": RELEASE, "client": "killed",
         "token": reached[1].token,
         "host": "127.0.0.1", "port": controller.port, "options": {"interval": 0.05}}
    )  # fmt: skip
    assert gone.receive()["op"] == "welcome"
    gone.send({"op": "line", "seq": 1, "what": "watch I 20", "line": "watch I 20"})
    b = client(running.target)
    try:
        b.run("watch I 21")
        b.until(lambda: controller.lines.count(b"GET:RC8:20:I:") >= 2, "the killed one's polls")
        gone.sock.close()
        b.until(lambda: len(running.agent.clients) == 1, "the killed one gone")
        left = controller.lines.count(b"GET:RC8:20:I:")
        ours = controller.lines.count(b"GET:RC8:21:I:")
        b.until(lambda: controller.lines.count(b"GET:RC8:21:I:") >= ours + 5, "five more polls")
    finally:
        b.engine.stop()
    assert controller.lines.count(b"GET:RC8:20:I:") == left


def test_connect_elsewhere_through_the_agent_never_writes_to_the_held_controller(
    agent_dir: Path, recording
) -> None:
    held: RecordingServer = recording(Memory())
    other: RecordingServer = recording(Memory())
    running = Running(held, Target("127.0.0.1", held.port, read_only=True))
    a = client(Target("127.0.0.1", held.port))
    try:
        a.run(f"connect 127.0.0.1:{other.port}")
        a.outcome("put I 1 5")
    finally:
        a.engine.stop()
        running.stop()
    assert not any(line.startswith(b"PUT") for line in held.lines)
    assert other.lines.count(b"PUT:RC8:1:I:3,5") == 1


def test_a_message_of_no_use_ends_that_client_and_its_polling(
    running: Running, controller: RecordingServer
) -> None:
    from rac_console.agent import endpoint
    from rac_console.agent.wire import PROTOCOL, RELEASE, Channel

    reached = endpoint.reach()
    assert reached is not None
    bad = Channel(reached[0])
    bad.send(
        {"op": "hello", "protocol": PROTOCOL, "release": RELEASE, "client": "bad",
         "token": reached[1].token,
         "host": "127.0.0.1", "port": controller.port, "options": {"interval": 0.05}}
    )  # fmt: skip
    assert bad.receive()["op"] == "welcome"
    bad.send({"op": "line", "seq": 1, "what": "watch I 30", "line": "watch I 30"})
    b = client(running.target)
    try:
        b.until(lambda: controller.lines.count(b"GET:RC8:30:I:") >= 2, "its polls")
        bad.send({"op": "line", "what": "get I 1"})  # no seq
        b.until(lambda: len(running.agent.clients) == 1, "the bad client gone")
        left = controller.lines.count(b"GET:RC8:30:I:")
        b.run("watch I 31")
        ours = controller.lines.count(b"GET:RC8:31:I:")
        b.until(lambda: controller.lines.count(b"GET:RC8:31:I:") >= ours + 5, "polls go on")
    finally:
        b.engine.stop()
        bad.close()
    assert controller.lines.count(b"GET:RC8:30:I:") == left


def test_a_write_waiting_for_an_earlier_clients_write_can_be_cancelled(
    agent_dir: Path, controller: RecordingServer
) -> None:
    """a's put arrived first and waits on its question; b's put (said yes) waits its
    turn behind it; Esc at b: b's PUT is never sent."""
    policy = WritePolicy(Writes.CONFIRM, None, "profile cell3")
    profile = TargetProfile("cell3", "127.0.0.1", controller.port, "Cell 3", "red", policy)
    running = Running(controller, Target("127.0.0.1", controller.port, profile, policy))
    a = client(running.target)  # never answers its question
    engine = attach(
        Target("127.0.0.1", controller.port), EngineOptions(timeout=5.0, interval=0.05),
        client="test", where=Where.CONSOLE,
    )  # fmt: skip
    assert isinstance(engine, RemoteEngine)
    engine.start()
    b = Answering(engine, yes=True)
    try:
        a.engine.submit("put I 2 5")
        a.until(lambda: _lines_received(running, "test 1") == 1, "a's put at the agent")
        put_b = engine.submit("put I 3 6")
        order = running.agent.held[0].connection.order
        b.until(lambda: order.waiting == 1, "b's put waiting its turn")
        engine.cancel()
        b.until(lambda: put_b in b.results, "b's put answered")
    finally:
        a.engine.stop()
        engine.stop()
        running.stop()
    assert not any(line.startswith(b"PUT") for line in controller.lines)
    (outcome,) = b.results[put_b].feedback
    assert "cancel" in str(getattr(outcome, "error", "")).lower(), outcome


def test_a_served_console_keeps_the_poll_bounds_serve_gave_it(
    running: Running, controller: RecordingServer
) -> None:
    from rac_console.engine.setup.poll_bounds import PollBounds

    options = EngineOptions(timeout=5.0, interval=1.0, bounds=PollBounds(0.7, 2))
    target = Target("127.0.0.1", controller.port, read_only=True, read_only_flag=True)
    engine = attach(target, options, client="served", where=Where.SERVED)
    assert isinstance(engine, RemoteEngine)
    engine.start()
    served = Front(engine)  # type: ignore[arg-type]
    try:
        too_many = served.errors("watch I 1-3")
        too_often = served.errors("interval 0.1")
        served.run("watch I 1")
    finally:
        engine.stop()
    assert too_many and "2" in too_many[0], too_many
    assert too_often and "0.7" in too_often[0], too_often
    polled = {line for line in controller.lines if line.startswith(b"GET")}
    assert polled <= {b"GET:RC8:1:I:"}  # nothing of the refused watch reached it


def test_poll_frames_beyond_the_budget_are_left_out_and_said_while_writes_come_whole(
    agent_dir: Path, controller: RecordingServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    from rac_console.agent import server

    monkeypatch.setattr(server, "POLL_FRAMES_PER_SECOND", 20)
    started = Running(controller)
    a = client(started.target)
    try:
        a.run("watch I 0-9")
        a.run("interval 0")
        a.until(lambda: any("not sent by the agent" in note for note in a.notes), "the note")
        assert a.outcome("put I 3 8").verified
        a.until(lambda: b"PUT:RC8:3:I:3,8\r" in a.sent(), "the PUT's frame")
    finally:
        a.engine.stop()
        started.stop()
    (said, *_) = [note for note in a.notes if "not sent by the agent" in note]
    assert "not sent by the agent (20/s at most)" in said
    put = [f for f in a.frames if f.data.startswith(b"PUT")]
    replies = [f for f in a.frames if f.direction == "rx" and f.request is not None
               and f.request.command == "PUT"]  # fmt: skip
    assert len(put) == len(replies) == 1  # the write and its answer, whatever was left out


def test_a_stopped_client_never_stops_the_polling_and_is_told_what_it_missed(
    running: Running, controller: RecordingServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    import socket

    from rac_console.agent import endpoint
    from rac_console.agent.wire import PROTOCOL, RELEASE, Channel
    from rac_console.engine.published import outbox

    monkeypatch.setattr(outbox, "MAX_EVENTS", 2_000)  # its queue's bound, reached sooner
    reached = endpoint.reach()
    assert reached is not None
    reached[0].setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    stopped = Channel(reached[0])  # a client that stops reading (a frozen terminal)
    stopped.send(
        {"op": "hello", "protocol": PROTOCOL, "release": RELEASE, "client": "stopped",
         "token": reached[1].token,
         "host": "127.0.0.1", "port": controller.port, "options": {"interval": 0}}
    )  # fmt: skip
    assert stopped.receive()["op"] == "welcome"
    stopped.send({"op": "line", "seq": 1, "what": "watch I 0-19", "line": "watch I 0-19"})
    (held,) = running.agent.clients.values()
    held.channel.sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)  # full sooner
    queue = held.engine.outbox if held.engine is not None else None
    assert queue is not None
    b = client(running.target)
    try:
        b.run("watch I 40")
        b.until(lambda: queue._batch.frames_dropped > 0, "the stopped one's queue full")
        polls = controller.lines.count(b"GET:RC8:40:I:")
        b.until(lambda: controller.lines.count(b"GET:RC8:40:I:") >= polls + 10, "b polled on")
        stopped.set_timeout(30)
        told = next(m for m in stopped.messages() if m.get("frames_dropped"))
        listed = {c["name"]: c["missed"] for c in running.agent.status()["clients"]}
    finally:
        b.engine.stop()
        stopped.close()
    assert told["frames_dropped"] > 0  # said to it, and in agent status
    assert listed[held.name] >= told["frames_dropped"]


def test_of_two_agents_started_at_once_the_second_is_told_one_runs(
    agent_dir: Path, controller: RecordingServer
) -> None:
    """The first holds the folder's lock and has not listened yet (a socket or port file
    left by an agent killed is still there): the second must not take its place."""
    from rac_console.agent import endpoint

    left, _ = endpoint.listen_socket()
    left.close()  # what an agent killed leaves behind
    starting = endpoint._lock(endpoint.folder())
    try:
        with pytest.raises(endpoint.EndpointError, match="an agent is already running"):
            endpoint.listen()
    finally:
        starting.close()
    again, _ = endpoint.listen()  # the lock went with the first: the next one starts
    again.close()


def test_a_port_left_by_a_dead_agent_and_taken_by_another_program_is_no_agent(
    agent_dir: Path, controller: RecordingServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Windows' endpoint (a loopback port and a token in a file), on any platform: a
    program that took the port an agent left answers without the token's proof, and
    the client goes direct; the agent's own answers carry it."""
    import json
    import socket

    from rac_console.agent import endpoint
    from rac_console.agent.wire import Channel

    monkeypatch.setattr(endpoint, "WINDOWS", True)
    taken = socket.create_server(("127.0.0.1", 0))
    heard: list[dict[str, object]] = []

    def impostor() -> None:
        sock, _ = taken.accept()
        channel = Channel(sock)
        heard.append(channel.receive())
        channel.send({"op": "welcome", "client": "impostor 1"})

    threading.Thread(target=impostor, daemon=True).start()
    agent_dir.mkdir(parents=True, exist_ok=True)
    left = {"port": taken.getsockname()[1], "token": "ab" * 16, "pid": 1}
    (agent_dir / endpoint.PORT_FILE).write_text(json.dumps(left), encoding="utf-8")
    target = Target("127.0.0.1", controller.port)
    options = EngineOptions(timeout=5.0)
    try:
        assert attach(target, options, client="test", where=Where.CONSOLE) is None
    finally:
        taken.close()
    assert heard and heard[0]["op"] == "hello"  # it was asked, and not believed
    running = Running(controller)  # a real agent (the port file is its own now)
    try:
        engine = attach(target, options, client="test", where=Where.CONSOLE)
        assert isinstance(engine, RemoteEngine)
        engine.start()
        assert Front(engine).outcome("put I 6 3").verified  # type: ignore[arg-type]
        engine.stop()
    finally:
        running.stop()
    assert controller.lines.count(b"PUT:RC8:6:I:3,3") == 1


def test_a_client_of_the_agents_simulator_is_told_its_values_went_with_it(
    agent_dir: Path,
) -> None:
    from rac_console.agent.client import AGENT_SIMULATOR_GONE
    from rac_console.sim.thread import SimulatorThread

    simulator = SimulatorThread().start()
    held = Target(simulator.host, simulator.port, simulated=True)
    agent = Agent([("sim", held)], timeout=5.0, say=lambda text: None,
                  simulators={"sim": simulator.stop})  # fmt: skip
    agent.open()
    threading.Thread(target=agent.serve, daemon=True).start()
    engine = attach(Target(None, 5006), EngineOptions(timeout=5.0), client="REPL", where=Where.REPL)
    assert isinstance(engine, RemoteEngine)
    engine.start()
    a = Front(engine)  # type: ignore[arg-type]
    try:
        assert a.outcome("put I 5 11").verified
        agent.stop()
        a.until(lambda: any("the agent stopped" in text for text in a.alerts), "the one line")
    finally:
        engine.stop()
    assert AGENT_SIMULATOR_GONE in a.alerts
    # Stopped as its own engine started: that engine and its simulator stop too.
    a.until(lambda: not {"rac-engine", "rac-sim"} & engine_threads(), "no engine left running")


def engine_threads() -> set[str]:
    return {thread.name for thread in threading.enumerate()}


def test_the_repls_toolbar_says_via_agent() -> None:
    from dataclasses import replace

    from rac_console.repl.prompt_parts import toolbar_fragments
    from tests.support.samples import CELL3

    shown = "".join(part[1] for part in toolbar_fragments(replace(CELL3, via="via agent")))
    alone = "".join(part[1] for part in toolbar_fragments(CELL3))
    assert "via agent" in shown and "via agent" not in alone


def test_a_client_that_records_its_frames_records_every_poll_whatever_the_budget(
    agent_dir: Path, controller: RecordingServer, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    import json

    from rac_console.agent import server

    monkeypatch.setattr(server, "POLL_FRAMES_PER_SECOND", 20)
    started = Running(controller)
    record = tmp_path / "client.jsonl"
    options = EngineOptions(timeout=5.0, interval=0.0, record=str(record))
    engine = attach(started.target, options, client="test", where=Where.CONSOLE)
    assert isinstance(engine, RemoteEngine)
    engine.start()
    a = Front(engine)  # type: ignore[arg-type]
    try:
        a.run("watch I 0-9")
        # 101 reads of I5: at least 101 cycles begun, more than 1,000 reads in all.
        a.until(lambda: controller.lines.count(b"GET:RC8:5:I:") >= 101, "a hundred cycles")
        a.run("pause")
    finally:
        engine.stop()
        started.stop()
    polled = sum(1 for line in controller.lines if line.startswith(b"GET"))
    lines = [json.loads(line) for line in record.read_text(encoding="utf-8").splitlines()]
    recorded = sum(1 for line in lines if line["dir"] == "tx" and line["text"].startswith("GET"))
    assert recorded == polled > 1000  # 20 a second would have kept a few dozen


def test_a_line_typed_while_the_client_goes_on_alone_runs_on_its_own_session(
    running: Running, controller: RecordingServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The agent gone, its one line said, and the client's own engine still starting: a
    line typed then never reached the agent; it runs once that engine is up, never
    answered "outcome unknown"."""
    from rac_console.agent import client as client_module
    from rac_console.engine import Engine

    starting = threading.Event()
    made = Engine

    def slow_engine(**given: object) -> object:
        assert starting.wait(FRONT_WAIT), "the test never let the engine start"
        return made(**given)  # type: ignore[arg-type]

    monkeypatch.setattr(client_module, "Engine", slow_engine)
    a = client(running.target)
    try:
        running.stop()
        a.until(lambda: any("the agent stopped" in text for text in a.alerts), "the one line")
        seq = a.engine.submit("get I 9")
        starting.set()
        a.until(lambda: seq in a.results, "its answer")
        (outcome,) = a.results[seq].feedback
    finally:
        starting.set()
        a.engine.stop()
    assert getattr(outcome, "ok", False), outcome
    assert controller.accepted == 2 and controller.lines.count(b"GET:RC8:9:I:") == 1


FRONT_WAIT = 30.0
