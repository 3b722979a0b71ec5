"""A write's outcome is never reported wrongly (issue 19, items 2, 4 and 5).

- A PUT that timed out may still land: the test holds its bytes "on the network" (a
  proxy written here) until the result is reported, then delivers them only if the
  client left its connection open for them (a graceful close; a reset discards them,
  as a kernel does with unsent data). The result must say the outcome is unknown, and
  nothing may land afterwards.
- A cancel between a write's GET before and its PUT sends nothing more.
- A GET that finds its reused connection dead before any byte of its reply is sent once
  more on a fresh connection; a PUT never is.
"""

from __future__ import annotations

import contextlib
import json
import socket
import threading
import time
from collections.abc import Callable, Iterator

import pytest

import rac_console as rac
from rac_console.commands.outcome import Outcome
from rac_console.engine import Engine
from rac_console.present.render import error_text
from rac_console.present.status import status_text
from rac_console.protocol.request import raw_request
from rac_console.session import Frame, NotSent, Session
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import Front, cli
from tests.support.servers import Memory, Recording, RecordingServer, fixed_reply, reset_first

DEADLINE = 20.0


def _until(condition: Callable[[], bool], what: str, deadline: float = DEADLINE) -> None:
    end = time.monotonic() + deadline
    while not condition():
        if time.monotonic() > end:
            raise AssertionError(f"not within {deadline} s: {what}")
        time.sleep(0.01)


class HoldingProxy:
    """127.0.0.1:0 in front of a simulator. Every line goes through at once, except the
    first PUT, which is held until :meth:`release`; then it is delivered if the client's
    connection is still open or was closed gracefully (a kernel would still be sending
    it), and discarded if the client reset the connection."""

    def __init__(self, upstream_port: int) -> None:
        self.upstream_port = upstream_port
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port: int = self._server.getsockname()[1]
        self._release = threading.Event()
        self.held = threading.Event()
        self.verdict: str | None = None  # "delivered" or "discarded", once decided
        self._held_once = False
        self._lock = threading.Lock()
        self._closing = False
        threading.Thread(target=self._accept, daemon=True).start()

    def release(self) -> None:
        self._release.set()

    def close(self) -> None:
        self._closing = True
        self._release.set()
        self._server.close()

    def _accept(self) -> None:
        while not self._closing:
            try:
                client, _ = self._server.accept()
            except OSError:
                return
            upstream = socket.create_connection(("127.0.0.1", self.upstream_port))
            threading.Thread(target=self._down, args=(upstream, client), daemon=True).start()
            threading.Thread(target=self._up, args=(client, upstream), daemon=True).start()

    def _down(self, upstream: socket.socket, client: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := upstream.recv(65536):
                client.sendall(data)

    def _up(self, client: socket.socket, upstream: socket.socket) -> None:
        buffer = b""
        with contextlib.suppress(OSError):
            while data := client.recv(65536):
                buffer += data
                while b"\r" in buffer:
                    line, buffer = buffer.split(b"\r", 1)
                    with self._lock:
                        hold = line.startswith(b"PUT") and not self._held_once
                        self._held_once = self._held_once or hold
                    if hold:
                        self._hold(client, upstream, line + b"\r")
                        return
                    upstream.sendall(line + b"\r")

    def _hold(self, client: socket.socket, upstream: socket.socket, line: bytes) -> None:
        self.held.set()
        self._release.wait(DEADLINE * 3)
        try:
            client.settimeout(DEADLINE)
            client.recv(65536)  # b"": closed gracefully, the kernel would still deliver
            self.verdict = "delivered"
            upstream.sendall(line)
        except ConnectionResetError:
            self.verdict = "discarded"  # reset: the unsent bytes died with it


def _sim_value(sim: SimulatorThread, index: int) -> str:
    with Session(sim.host, sim.port, timeout=2.0) as session:
        return session.exchange(raw_request(f"GET:RC8:{index}:I:")).text


@pytest.fixture
def sim() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


@pytest.fixture
def proxy(sim: SimulatorThread) -> Iterator[HoldingProxy]:
    holding = HoldingProxy(sim.port)
    yield holding
    holding.close()


@pytest.mark.slow
def test_a_timed_out_put_is_unknown_and_lands_nowhere_after_the_result(
    env: dict[str, str],
    sim: SimulatorThread,
    proxy: HoldingProxy,
) -> None:
    before = _sim_value(sim, 10)
    args = ["-H", "127.0.0.1", "-p", str(proxy.port), "--timeout", "2.0"]
    result = cli(env, *args, "put", "I", "10", "4242", "--json")
    assert proxy.held.is_set()
    proxy.release()  # the result is reported: now the network lets the PUT go
    _until(lambda: proxy.verdict is not None, "the held PUT delivered or discarded")
    assert result.returncode == 3, (result.stdout, result.stderr)
    data = json.loads(result.stdout)
    assert data["verified"] is None  # the read-back proves nothing about a timed-out PUT
    assert "outcome unknown" in data["error"] and "may still arrive" in data["error"]
    assert data["read_back"] is not None  # what the controller held then, said as such
    assert proxy.verdict == "discarded"
    assert _sim_value(sim, 10) == before


@pytest.mark.slow
def test_a_timed_out_put_is_unknown_in_plain_text_too(
    env: dict[str, str],
    sim: SimulatorThread,
    proxy: HoldingProxy,
) -> None:
    args = ["-H", "127.0.0.1", "-p", str(proxy.port), "--timeout", "2.0"]
    result = cli(env, *args, "put", "I", "10", "4242")
    proxy.release()
    assert result.returncode == 3
    assert "outcome unknown" in result.stderr and "not the value written" not in result.stderr
    assert "read back 0 just after, which proves nothing" in result.stderr, result.stderr
    assert "✗" not in result.stderr + result.stdout


@pytest.mark.slow  # over half a second
def test_the_console_says_a_timed_out_put_is_unknown(
    sim: SimulatorThread, proxy: HoldingProxy
) -> None:
    engine = Engine("127.0.0.1", proxy.port, interval=0.05, timeout=2.0)
    engine.start()
    try:
        front = Front(engine)
        seq = engine.submit("put I 10 4242")
        front.until(lambda: seq in front.results, "the put's result")
        [outcome] = front.results[seq].feedback
        assert isinstance(outcome, Outcome)
        said = error_text(outcome)  # as the console and the REPL show it
    finally:
        engine.stop()
        proxy.release()
    assert "outcome unknown" in said and "may still arrive" in said, said
    assert "✗" not in said and "not the value written" not in said, said


# ------------------------------------------------------------------ cancel


def test_a_cancel_between_the_get_before_and_the_put_sends_nothing_more(
    sim: SimulatorThread,
) -> None:
    engine = Engine(sim.host, sim.port, interval=0.05, timeout=1.0)
    engine.start()
    sent: list[bytes] = []
    try:

        def cancel_after_the_read_before(frame: Frame) -> None:
            if frame.direction == "tx":
                sent.append(bytes(frame.data))
            elif frame.direction == "rx" and sent == [b"GET:RC8:10:I:\r"]:
                engine.cancel()  # Esc, right after the GET before was answered

        engine.add_frame_observer(cancel_after_the_read_before)
        front = Front(engine)
        said = "\n".join(front.run("put I 10 77"))
    finally:
        engine.stop()
    assert "not sent: cancelled" in said, said
    assert not any(line.startswith(b"PUT") for line in sent), sent
    assert _sim_value(sim, 10) != "0,3,77"


def test_a_cancelled_job_sends_nothing_even_on_a_fresh_session(sim: SimulatorThread) -> None:
    with Session(sim.host, sim.port, timeout=1.0) as session:
        frames: list[Frame] = []
        session.add_frame_observer(frames.append)
        with pytest.raises(NotSent):
            session.exchange(raw_request("PUT:RC8:10:I:3,5"), cancelled=lambda: True)
        session.cancel()  # a cancel while idle is not eaten by the next exchange either
        with pytest.raises(NotSent):
            session.exchange(raw_request("PUT:RC8:10:I:3,5"), cancelled=lambda: True)
    assert frames == []


# ------------------------------------------------------- dead connections


def get_7_else_0(line: bytes) -> bytes:
    return b"0,3,7\r" if line.startswith(b"GET") else b"0\r"


@pytest.fixture
def dropping(recording: Recording) -> Callable[..., RecordingServer]:
    """A controller that answers every line (a GET ``0,3,7``, anything else ``0``), except
    that a line starting with one of ``drop`` ends its connection with a reset,
    unanswered, the first time it comes. It records every line and the connection it
    came on (``numbered``)."""

    def make(*drop: bytes) -> RecordingServer:
        return recording(reset_first(*drop, then=get_7_else_0))

    return make


@pytest.mark.slow
def test_a_get_on_a_dead_connection_is_sent_once_more(
    env: dict[str, str],
    dropping: Callable[..., RecordingServer],
) -> None:
    server = dropping(b"GET:RC8:2:I:")
    script = "get I 1\nget I 2\n"
    result = cli(env, "-H", "127.0.0.1", "-p", str(server.port), "run", "-", stdin=script)
    assert result.returncode == 0, (result.stdout, result.stderr)
    assert result.stdout.count("7") >= 2
    assert [line for _, line in server.numbered].count(b"GET:RC8:2:I:") == 2
    assert server.numbered[-1][0] == 2  # the second time on a fresh connection


@pytest.mark.slow
def test_a_put_on_a_dead_connection_is_never_sent_twice(
    env: dict[str, str],
    dropping: Callable[..., RecordingServer],
) -> None:
    server = dropping(b"PUT:RC8:2:I:")
    script = "get I 1\nput I 2 5\n"
    result = cli(env, "-H", "127.0.0.1", "-p", str(server.port), "run", "-", stdin=script)
    assert result.returncode == 3, (result.stdout, result.stderr)
    assert [line for _, line in server.numbered].count(b"PUT:RC8:2:I:3,5") == 1


@pytest.mark.slow  # over half a second
def test_an_idle_engine_notices_its_connection_died(
    dropping: Callable[..., RecordingServer],
) -> None:
    """The controller ends the connection while nothing is watched or typed: the status
    and the log say so without waiting for the next command."""
    server = dropping()
    engine = Engine("127.0.0.1", server.port, interval=0.05, timeout=1.0)
    engine.start()
    try:
        front = Front(engine)
        front.run("get I 1")
        front.until(
            lambda: front.status is not None and front.status.connection == "connected", "connected"
        )
        server.hang_up()
        front.until(
            lambda: front.status is not None and front.status.connection == "lost",
            "the idle connection seen closed",
        )
        assert any("closed the connection" in alert for alert in front.alerts), front.alerts
        assert front.status is not None
        shown = status_text(front.status, None, 0.0).plain
        assert "lost, the next command reconnects" in shown, shown
    finally:
        engine.stop()


def test_a_get_sent_again_is_marked_in_the_log(
    dropping: Callable[..., RecordingServer],
) -> None:
    server = dropping(b"GET:RC8:2:I:")
    engine = Engine("127.0.0.1", server.port, interval=0.05, timeout=1.0)
    engine.start()
    try:
        front = Front(engine)
        front.run("get I 1")
        seq = engine.submit("get I 2")
        front.until(lambda: seq in front.results, "the answer to get I 2")
        [outcome] = front.results[seq].feedback
        assert isinstance(outcome, Outcome) and outcome.ok, outcome
        assert any("sent again on a fresh connection" in note for note in front.notes)
        assert front.sent().count(b"GET:RC8:2:I:\r") == 2
    finally:
        engine.stop()


# ------------------------------------------------------------------ unanswered writes


def _garbles_puts(line: bytes) -> bytes | None:
    """A controller that answers its GETs and answers a PUT with a line that is no RAC."""
    return b"garbage\r" if line.startswith(b"PUT") else Memory()(line)  # type: ignore[return-value]


@pytest.mark.parametrize(
    ("reply", "args", "says"),
    [
        (_garbles_puts, ("put", "I", "10", "5"), "outcome unknown, the PUT may have been applied"),
        (
            fixed_reply(None),
            ("--timeout", "0.5", "send", "HELLO"),
            "outcome unknown, the line may have written or may still arrive",
        ),
    ],
    ids=["a PUT answered with no RAC", "a line not a GET unanswered"],
)
def test_a_write_that_went_out_unanswered_is_said_unknown_by_the_console_and_the_library(
    env: dict[str, str],
    recording: Recording,
    reply: Callable[[bytes], bytes | None],
    args: tuple[str, ...],
    says: str,
) -> None:
    """Whatever cut the answer off, a write that went out is said unknown, once, by the
    command line and by a script (whose ``OutcomeUnknown`` reads the outcome's
    ``write_unknown``): never a lost connection or an unreadable reply."""
    server = recording(reply)
    result = cli(env, *server.args, *args)
    assert result.returncode == 3, result.stderr
    assert result.stderr.count("outcome unknown") == 1 and says in result.stderr
    writes = [line for line in server.lines if not line.startswith(b"GET")]
    assert len(writes) == 1  # never sent again
    server.lines.clear()
    with (
        rac.connect(f"127.0.0.1:{server.port}", timeout=0.5) as rc,
        pytest.raises(rac.OutcomeUnknown) as unknown,
    ):
        if args[-1] == "HELLO":
            rc.send("HELLO")
        else:
            rc.put("I", 10, 5)
    assert str(unknown.value).count("outcome unknown") == 1 and says in str(unknown.value)
    assert [line for line in server.lines if not line.startswith(b"GET")] == writes
