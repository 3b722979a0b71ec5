"""``rac-console sim --replay CELL.jsonl`` and ``rac-console sim --cell N`` as a user
runs them: a subprocess on 127.0.0.1 port 0, each simulator asked over a plain socket.

Every wait has a deadline; nothing sleeps and hopes.
"""

from __future__ import annotations

import json
import queue
import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

DEADLINE = 15.0
SIM = [sys.executable, "-m", "rac_console", "sim", "--port", "0"]


def frame(target: str | None, direction: str, text: str, t: float) -> str:
    line: dict[str, object] = {"t": t}
    if target is not None:
        line["target"] = target
    line.update(dir=direction, text=text)
    return json.dumps(line)


#: A cell's recording: the targets' lines interleaved, each answering its own requests.
CELL_RECORDING = [
    frame("robotA", "tx", "GET:RC8:10:I:", 1.0),
    frame("robotB", "tx", "GET:RC8:10:I:", 1.1),
    frame("robotA", "rx", "0,3,11", 1.2),
    frame("robotB", "rx", "0,3,22", 1.3),
    frame("robotB", "tx", "GET:RC8:10:I:", 1.4),
    frame("robotB", "rx", "0,3,23", 1.5),
]


class Sim:
    """A running ``rac-console sim``: its stdout lines as they come."""

    def __init__(self, args: list[str], environment: dict[str, str]) -> None:
        self.process = subprocess.Popen(
            [*SIM, *args],
            env=environment,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            encoding="utf-8",
        )
        self.lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.put(line.rstrip("\n"))

    def listening(self, count: int) -> dict[str, int]:
        """The first ``count`` ``NAME listening on HOST:PORT`` lines: port by name."""
        found: dict[str, int] = {}
        while len(found) < count:
            line = self.lines.get(timeout=DEADLINE)
            name, said, address = line.partition(" listening on ")
            if said:
                host, _, port = address.split()[0].rpartition(":")
                assert host == "127.0.0.1", line
                found[name] = int(port)
        return found


@pytest.fixture
def sim(env: dict[str, str]) -> Iterator[Callable[..., Sim]]:
    started: list[Sim] = []

    class Started(Sim):
        def __init__(self, args: list[str], environment: dict[str, str] = env) -> None:
            super().__init__(args, environment)
            started.append(self)

    yield Started
    for one in started:
        if one.process.poll() is None:
            one.process.kill()
        one.process.communicate(timeout=DEADLINE)


def ask(port: int, line: bytes) -> bytes:
    """One request over a plain socket; the reply up to its CR."""
    with socket.create_connection(("127.0.0.1", port), timeout=DEADLINE) as conn:
        conn.sendall(line + b"\r")
        reply = b""
        while not reply.endswith(b"\r"):
            data = conn.recv(4096)
            assert data, f"closed after {reply!r}"
            reply += data
    return reply


def test_a_recorded_cell_replays_each_target_on_its_own_port(
    sim: Callable[..., Sim], tmp_path: Path
) -> None:
    path = tmp_path / "cell.jsonl"
    path.write_text("\n".join(CELL_RECORDING) + "\n")
    running = sim(["--replay", str(path)])
    ports = running.listening(2)
    assert set(ports) == {"robotA", "robotB"} and ports["robotA"] != ports["robotB"]
    assert ask(ports["robotA"], b"GET:RC8:10:I:") == b"0,3,11\r"
    assert ask(ports["robotB"], b"GET:RC8:10:I:") == b"0,3,22\r"
    assert ask(ports["robotB"], b"GET:RC8:10:I:") == b"0,3,23\r"
    assert ask(ports["robotA"], b"GET:RC8:10:I:") == b"0,3,11\r"  # held, never invented


def test_a_file_mixing_a_cell_and_no_cell_is_refused_in_one_line(
    env: dict[str, str],
    tmp_path: Path,
) -> None:
    path = tmp_path / "mixed.jsonl"
    lines = [frame(None, "tx", "GET:RC8:1:I:", 0.5), frame(None, "rx", "0,3,1", 0.6)]
    path.write_text("\n".join([*lines, *CELL_RECORDING]) + "\n")
    result = subprocess.run(
        [*SIM, "--replay", str(path)], env=env, capture_output=True, text=True, timeout=DEADLINE
    )
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and "replay them apart" in result.stderr


def test_sim_cell_starts_n_simulators_each_answering_and_ctrl_c_stops_all(
    sim: Callable[..., Sim],
) -> None:
    running = sim(["--cell", "2"])
    ports = running.listening(2)
    assert list(ports) == ["robotA", "robotB"]
    for port in ports.values():
        assert ask(port, b"GET:RC8:0:IO:").startswith(b"0,")
        assert ask(port, b"GET:RC8:10:I:").startswith(b"0,3,")
    running.process.send_signal(signal.SIGINT)
    assert running.process.wait(timeout=DEADLINE) == 130  # interrupted, as one simulator
    for port in ports.values():
        with pytest.raises(OSError):
            socket.create_connection(("127.0.0.1", port), timeout=DEADLINE).close()


def test_sim_cell_and_replay_together_are_refused(
    env: dict[str, str],
    tmp_path: Path,
) -> None:
    path = tmp_path / "cell.jsonl"
    path.write_text("\n".join(CELL_RECORDING) + "\n")
    result = subprocess.run(
        [*SIM, "--cell", "2", "--replay", str(path)],
        env=env,
        capture_output=True,
        text=True,
        timeout=DEADLINE,
    )
    assert result.returncode == 2
    assert "--cell" in result.stderr and "--replay" in result.stderr
