"""The simulator against abusive clients: stderr stays quiet, memory stays flat, file
descriptors run out calmly, and control lines take only sane values.

Real loopback sockets on 127.0.0.1 port 0. Where stderr, RSS or file descriptors are
measured, ``rac-console sim --port 0`` runs as a subprocess (Linux: /proc). Every loop
is bounded in count and time, every wait has a deadline, and each test stops what it
started. The full-size figures are in ``benchmarks/sim_abuse.py``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from rac_console.cli.main import build_parser
from rac_console.protocol import hresult, parse_response
from rac_console.sim.controller import SimulatedController
from rac_console.sim.faults import FaultSettings
from rac_console.sim.server import SimulatorServer

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

try:
    import resource
except ImportError:  # not POSIX
    resource = None  # type: ignore[assignment]

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmark's misbehaving clients, reused
from sim_harness import HOST, PROBE, PROBE_REPLY, SimulatorProcess, ask, hostile  # noqa: E402

LONG_TEXT = "x" * 240  # PUT:RC8:10:S:8,<240> + CR is exactly 256 bytes
HAS_PROC = Path("/proc/self/status").exists()
needs_proc = pytest.mark.skipif(not HAS_PROC, reason="measures the process through /proc")


# ------------------------------------------------------------------- helpers


def wait_for(predicate: Callable[[], bool], timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.02)


def storm(port: int, count: int, threads: int = 8) -> None:
    workers = [
        threading.Thread(target=lambda w=w: [hostile(port, n) for n in range(w, count, threads)])
        for w in range(threads)
    ]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(60)
        assert not worker.is_alive()


def quiet(text: str) -> list[str]:
    """What a user would call noise in stderr."""
    return [line for line in text.splitlines() if "Traceback" in line or "raised exception" in line]


# ------------------------------------------------------ 1. stderr stays quiet


@needs_proc
def test_hostile_connections_leave_stderr_small(tmp_path: Path) -> None:
    with SimulatorProcess(pythonpath=str(ROOT)) as sim:
        baseline = sim.fds()
        storm(sim.port, 2000)
        assert ask(sim.port, 10) is not None
        # every hostile connection gone from the simulator: its last writes have failed
        wait_for(lambda: sim.fds() <= baseline, 15, "the hostile connections to close")
        assert ask(sim.port, 10) is not None
        text = sim.stderr()
    assert quiet(text) == []
    assert len(text.splitlines()) <= 3, text[:2000]


@needs_proc
def test_stderr_nobody_reads_does_not_stop_it(tmp_path: Path) -> None:
    with SimulatorProcess(stderr_pipe=True, pythonpath=str(ROOT)) as sim:
        storm(sim.port, 2000)
        assert ask(sim.port, 10) is not None, "no answer with stderr on an undrained pipe"


@pytest.mark.parametrize("faults", [{}, {"delay_ms": 0.01}], ids=["fast-path", "fault-path"])
def test_no_write_to_a_connection_already_gone(
    faults: dict[str, Any], caplog: pytest.LogCaptureFixture
) -> None:
    """asyncio warns ``socket.send() raised exception.`` for each write to a lost
    connection; the simulator makes none."""

    async def scenario() -> bytes:
        async with SimulatorServer(faults=FaultSettings(**faults)) as sim:
            for _ in range(40):
                reader, writer = await asyncio.open_connection(sim.host, sim.port)
                writer.write(b"GET:RC8:1:P:\r" * 50)
                await writer.drain()
                writer.transport.abort()  # gone, with the replies unread: an RST
            deadline = time.monotonic() + 10
            while sim.sessions and time.monotonic() < deadline:
                await asyncio.sleep(0.02)
            reader, writer = await asyncio.open_connection(sim.host, sim.port)
            writer.write(PROBE)
            reply = await asyncio.wait_for(reader.readuntil(b"\r"), 5)
            writer.close()
            return reply

    with caplog.at_level(logging.WARNING, logger="asyncio"):
        assert asyncio.run(scenario()) == PROBE_REPLY
    assert [r.getMessage() for r in caplog.records if r.name == "asyncio"] == []


# --------------------------------------- 2. clients that never read are paused


def deaf_client(port: int) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 256 * 1024)
    sock.settimeout(5)
    sock.connect((HOST, port))
    sock.setblocking(False)
    return sock


class NormalClient(threading.Thread):
    """Asks the probe on one connection, again and again, until stopped."""

    def __init__(self, port: int, deadline: float) -> None:
        super().__init__(daemon=True)
        self.port, self.deadline = port, deadline
        self.rtts: list[float] = []
        self.failed = False
        self.stop = threading.Event()

    def run(self) -> None:
        with socket.create_connection((HOST, self.port), timeout=self.deadline) as sock:
            while not self.stop.is_set():
                rtt = ask(self.port, self.deadline, sock)
                if rtt is None:
                    self.failed = True
                    return
                self.rtts.append(rtt)
                self.stop.wait(0.02)


@needs_proc
def test_clients_that_never_read_cost_flat_memory_and_starve_no_one(tmp_path: Path) -> None:
    """150 clients send requests with long replies (an S variable of 240 characters) and
    never read. The simulator's RSS may grow by 16 MB at most (about 110 KB a client;
    it grows about 2 MB), and a normal client is answered all along, each request within
    10 s (it takes well under a second)."""
    count, bound_kb = 150, 16 * 1024
    with SimulatorProcess(pythonpath=str(ROOT)) as sim, contextlib.ExitStack() as stack:
        with socket.create_connection((HOST, sim.port), timeout=5) as setup:
            setup.sendall(f"PUT:RC8:10:S:8,{LONG_TEXT}\r".encode())
            assert setup.recv(10) == b"0\r"
        baseline = sim.rss_kb()
        peak = baseline
        normal = NormalClient(sim.port, 10)
        normal.start()
        stack.callback(normal.join, 30)
        stack.callback(normal.stop.set)
        clients = [deaf_client(sim.port) for _ in range(count)]
        for sock in clients:
            stack.callback(sock.close)
        chunk = b"GET:RC8:10:S:\r" * 300
        refusals = dict.fromkeys(clients, 0)
        started = time.monotonic()
        while refusals and time.monotonic() - started < 20:  # until none can send
            progress = False
            for sock in list(refusals):
                try:
                    sock.send(chunk)
                    refusals[sock], progress = 0, True
                except BlockingIOError:
                    refusals[sock] += 1
                    if refusals[sock] >= 20:
                        del refusals[sock]
            peak = max(peak, sim.rss_kb())
            if not progress:
                time.sleep(0.01)
        # then until the simulator has done what it will do (under 5% CPU for 0.5 s)
        last = (time.monotonic(), sim.cpu_seconds())
        settle = time.monotonic() + 20
        while time.monotonic() < settle:
            time.sleep(0.5)
            peak = max(peak, sim.rss_kb())
            now = (time.monotonic(), sim.cpu_seconds())
            idle = (now[1] - last[1]) / (now[0] - last[0]) < 0.05
            last = now
            if idle:
                break
        normal.stop.set()
        normal.join(30)
        problems = [
            *(["a normal request waited over 10 s"] if normal.failed else []),
            *(["the normal client was never answered"] if not normal.rtts else []),
            *(
                [f"RSS grew {(peak - baseline) / 1024:.0f} MB"]
                if peak - baseline > bound_kb
                else []
            ),
            *quiet(sim.stderr()),
        ]
        assert problems == []


@pytest.mark.parametrize("faults", [{}, {"slow_every": 10**9}], ids=["fast-path", "fault-path"])
def test_a_paused_session_answers_everything_in_order_once_read(faults: dict[str, Any]) -> None:
    """A client sends 36,000 requests (7 MB of replies, more than the OS buffers hold)
    before it reads any reply: it gets every answer, in order, and meanwhile the
    simulator holds at most 32 KiB of replies for it."""
    count = 36_000
    long_reply = b"GET:RC8:10:S:"
    cycle = [*[long_reply] * 3, b"GET:RC8:1:P:", *[long_reply] * 3, b"GET:RC8:2:I:"]
    lines = [cycle[n % len(cycle)] for n in range(count)]
    put = f"PUT:RC8:10:S:8,{LONG_TEXT}".encode()
    fresh = SimulatedController()
    fresh.handle(put)
    expected = [fresh.handle(line)[0][:-1] for line in lines]

    async def scenario() -> tuple[list[bytes], int]:
        controller = SimulatedController()
        controller.handle(put)
        async with SimulatorServer(controller=controller, faults=FaultSettings(**faults)) as sim:
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.setblocking(False)
            loop = asyncio.get_running_loop()
            await loop.sock_connect(sock, (sim.host, sim.port))
            sending = loop.create_task(loop.sock_sendall(sock, b"\r".join(lines) + b"\r"))
            buffered = 0
            deadline = time.monotonic() + 2
            while time.monotonic() < deadline:  # replies unread: the session must pause
                await asyncio.sleep(0.05)
                sizes = [
                    s._transport.get_write_buffer_size()
                    for s in sim.sessions
                    if s._transport is not None
                ]
                buffered = max([buffered, *sizes])
            replies = bytearray()
            while replies.count(b"\r") < count:
                replies += await asyncio.wait_for(loop.sock_recv(sock, 1 << 20), 10)
            await asyncio.wait_for(sending, 5)
            sock.close()
            return bytes(replies).split(b"\r")[:-1], buffered

    replies, buffered = asyncio.run(scenario())
    assert len(replies) == count
    assert [n for n, reply in enumerate(replies) if reply != expected[n]] == []
    assert buffered <= 32 * 1024, f"{buffered} bytes held for a client that does not read"


# ------------------------------------------------------- 3. file descriptors


def lowered_fd_limit(limit: int) -> Callable[[], None]:
    def lower() -> None:
        assert resource is not None
        _, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
        resource.setrlimit(resource.RLIMIT_NOFILE, (limit, hard))

    return lower


@needs_proc
@pytest.mark.skipif(resource is None, reason="RLIMIT_NOFILE is POSIX")
def test_out_of_file_descriptors_it_keeps_serving(tmp_path: Path) -> None:
    """With RLIMIT_NOFILE 256 and 300 idle connections, a new normal client is still
    answered, stderr has a line or two and no traceback, and the process lives on."""
    limit, idle = 256, 300
    with (
        SimulatorProcess(preexec=lowered_fd_limit(limit), pythonpath=str(ROOT)) as sim,
        contextlib.ExitStack() as stack,
    ):
        for _ in range(idle):
            sock = socket.create_connection((HOST, sim.port), timeout=5)
            stack.callback(sock.close)
        wait_for(lambda: sim.fds() >= limit - 16, 10, "the simulator to take connections")
        assert ask(sim.port, 15) is not None, "a new client was never answered"
        assert ask(sim.port, 15) is not None
        assert sim.process.poll() is None
        assert sim.fds() <= limit
        text = sim.stderr()
    assert "Traceback" not in text
    assert 1 <= len(text.splitlines()) <= 3, text[:2000]
    assert "file descriptors" in text


def test_idle_sessions_are_closed_after_idle_timeout() -> None:
    async def scenario() -> tuple[bytes, list[float], int]:
        async with SimulatorServer(idle_timeout=0.5) as sim:
            idle_reader, _ = await asyncio.open_connection(sim.host, sim.port)
            busy_reader, busy = await asyncio.open_connection(sim.host, sim.port)
            rtts = []
            started = time.monotonic()
            for _ in range(24):  # over 1.2 s of asking every 0.05 s: never idle 0.5 s
                busy.write(PROBE)
                await asyncio.wait_for(busy_reader.readuntil(b"\r"), 5)
                rtts.append(time.monotonic() - started)
                await asyncio.sleep(0.05)
            closed = await asyncio.wait_for(idle_reader.read(10), 5)
            sessions = len(sim.sessions)
            busy.close()
            return closed, rtts, sessions

    closed, rtts, sessions = asyncio.run(scenario())
    assert closed == b""
    assert len(rtts) == 24 and sessions == 1


def test_idle_timeout_option() -> None:
    parser = build_parser()
    assert parser.parse_args(["sim"]).idle_timeout == 0
    assert parser.parse_args(["sim", "--idle-timeout", "30"]).idle_timeout == 30.0
    for bad in ("inf", "nan", "-1", "x"):
        with pytest.raises(SystemExit) as exited:
            parser.parse_args(["sim", "--idle-timeout", bad])
        assert exited.value.code == 2


# ------------------------------------------------------------ 4. control lines


FLOAT_SETTINGS = ["delay_ms", "jitter_ms", "error_rate", "extra_gap_ms"]
BAD_VALUES = ["inf", "-inf", "nan", "1e400"]


@pytest.mark.parametrize("name", FLOAT_SETTINGS)
def test_control_line_refuses_values_that_are_not_finite(name: str) -> None:
    async def scenario() -> tuple[list[bytes], bytes, bytes]:
        async with SimulatorServer() as sim:
            reader, writer = await asyncio.open_connection(sim.host, sim.port)

            async def say(line: bytes) -> bytes:
                writer.write(line + b"\r")
                return await asyncio.wait_for(reader.readuntil(b"\r"), 5)

            refused = [await say(f"SIM:SET:{name}={bad}".encode()) for bad in BAD_VALUES]
            state = await say(b"SIM:GET:")
            answer = await say(PROBE[:-1])  # answered at once: nothing was changed
            writer.close()
            return refused, state, answer

    refused, state, answer = asyncio.run(scenario())
    assert {parse_response(r[:-1].decode()).code for r in refused} == {hresult.E_INVALIDARG}
    assert state == b"0,8," + FaultSettings().describe().encode() + b"\r"
    assert answer == PROBE_REPLY


@pytest.mark.parametrize(
    "assignment",
    ["delay_ms=60001", "jitter_ms=60001", "error_rate=1.01", "extra_gap_ms=60001"],
)
def test_settings_have_maxima(assignment: str) -> None:
    with pytest.raises(ValueError, match=assignment.split("=")[0]):
        FaultSettings().updated(assignment)
    name, value = assignment.split("=")
    with pytest.raises(ValueError, match=name):
        FaultSettings(**{name: float(value)}).check()  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=name):
        FaultSettings(**{name: float("inf")}).check()  # type: ignore[arg-type]
    assert FaultSettings().updated(f"{name}={float(value) * 0.99}")  # just under: fine


@pytest.mark.parametrize(
    "option", [["--delay", "inf"], ["--jitter", "nan"], ["--error-rate", "inf"], ["--delay", "1e9"]]
)
def test_command_line_refuses_values_that_are_not_finite(option: list[str]) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "sim", "--port", "0", *option],
        capture_output=True,
        text=True,
        timeout=15,
        cwd=ROOT,
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    said = [line for line in result.stderr.splitlines() if not line.startswith(("usage:", " "))]
    assert len(said) == 1, result.stderr  # one line (after argparse's usage, if it said it)
    assert "listening" not in result.stdout


@pytest.mark.parametrize("faults", [{}, {"delay_ms": 0.01}], ids=["fast-path", "fault-path"])
def test_no_control_answers_sim_lines_as_unknown_commands(faults: dict[str, Any]) -> None:
    async def scenario() -> list[bytes]:
        server = SimulatorServer(faults=FaultSettings(**faults), control=False)
        async with server as sim:
            reader, writer = await asyncio.open_connection(sim.host, sim.port)
            replies = []
            for line in (b"SIM:SET:garble_every=1", b"SIM:GET:", PROBE[:-1]):
                writer.write(line + b"\r")
                replies.append(await asyncio.wait_for(reader.readuntil(b"\r"), 5))
            writer.close()
            return replies

    set_reply, get_reply, probe = asyncio.run(scenario())
    for reply in (set_reply, get_reply):
        assert parse_response(reply[:-1].decode()).code == hresult.E_INVALIDCOMMAND
    assert probe == PROBE_REPLY  # garble_every was not set


def test_no_control_option() -> None:
    parser = build_parser()
    assert parser.parse_args(["sim"]).no_control is False
    assert parser.parse_args(["sim", "--no-control"]).no_control is True


# ------------------------------------------------------------------ notices


def test_notices_are_rate_limited_and_summed_up() -> None:
    from rac_console.sim.notices import Notices

    now = [0.0]
    lines: list[str] = []
    timers: list[tuple[float, Callable[[], None]]] = []
    notices = Notices(
        lines.append, window=10, clock=lambda: now[0], schedule=lambda d, f: timers.append((d, f))
    )
    for _ in range(1000):
        notices.note("fds", "out of file descriptors")
    assert lines == ["rac-console sim: out of file descriptors"]
    assert len(timers) == 1
    now[0] = 10
    timers.pop()[1]()
    assert len(lines) == 2 and "999 more" in lines[1]
    now[0] = 30
    for fire in [f for _, f in timers]:
        fire()
    notices.note("fds", "out of file descriptors")  # quiet for a window: at once again
    assert len(lines) == 3 and notices.counts["fds"] == 1001


def test_what_asyncio_would_print_becomes_one_line_without_traceback() -> None:
    """``rac-console sim`` routes asyncio's error reports and log warnings through the
    rate-limited notices: a thousand failing callbacks make one line, no traceback."""
    from rac_console.cli.simulator import _quiet_asyncio
    from rac_console.sim.notices import Notices

    lines: list[str] = []
    notices = Notices(lines.append)  # no timer: summaries would come a window later
    loop = asyncio.new_event_loop()
    handler = _quiet_asyncio(loop, notices)
    try:
        for _ in range(1000):
            loop.call_soon(lambda: 1 / 0)
        for _ in range(1000):
            logging.getLogger("asyncio").warning("socket.send() raised exception.")
        loop.run_until_complete(asyncio.sleep(0))
    finally:
        loop.close()
        logging.getLogger("asyncio").removeHandler(handler)
        logging.getLogger("asyncio").propagate = True
    assert len(lines) == 2, lines
    assert "ZeroDivisionError" in lines[0] or "ZeroDivisionError" in lines[1]
    assert not any("Traceback" in line or "\n" in line for line in lines)
