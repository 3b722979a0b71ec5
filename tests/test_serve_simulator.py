"""Without -H a served session talks to a built-in simulator of its own, which listens on
no port: the console reaches it over a socket pair of its own process, so no other
process or user of the machine serving it can read or write it. Judged from the
machine's side: the sockets the session's process listens on, read from /proc."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from rac_console.commands.outcome import Outcome
from rac_console.engine import Engine
from rac_console.engine.setup.where import Where
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import Front
from tests.support.serving import consoles_of, open_console, start_serve, until

#: /proc/net/unix's flag of a listening socket (__SO_ACCEPTCON); TCP's LISTEN state.
UNIX_LISTENING = 0x10000
TCP_LISTEN = "0A"


def listening(pid: int) -> list[str]:
    """The sockets process ``pid`` listens on: TCP (v4 and v6) and Unix, by /proc."""
    fds = Path(f"/proc/{pid}/fd")
    inodes = set()
    for fd in fds.iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[len("socket:[") : -1])
    found = []
    for table in ("tcp", "tcp6"):
        for line in Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == TCP_LISTEN and fields[9] in inodes:
                found.append(f"{table} {fields[1]}")
    for line in Path(f"/proc/{pid}/net/unix").read_text().splitlines()[1:]:
        fields = line.split()
        if int(fields[3], 16) & UNIX_LISTENING and fields[6] in inodes:
            found.append(f"unix {fields[7] if len(fields) > 7 else '(unnamed)'}")
    return found


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_served_sessions_simulator_listens_on_no_port(env, running) -> None:
    pytest.importorskip("textual_serve", reason="needs the extra web")
    served = start_serve(env, running, "--allow-writes")
    console = open_console(served)
    console.until("SERVED", "connected")
    console.type_line("put I 10 5")  # writes open: the simulator's own rules
    console.until("read back 5")
    console.type_line("watch I 1")
    console.until("watching I1")
    (pid,) = consoles_of(served.running.process.pid)
    assert listening(pid) == [], "the session's simulator can be reached from outside it"
    console.close()
    until(lambda: consoles_of(served.running.process.pid) == [], "the console ending")


def test_a_simulator_that_listens_nowhere_is_reached_through_its_thread_only() -> None:
    with SimulatorThread(listen=False) as simulator:
        assert simulator.port == 0 and simulator.server._sockets == []
        with simulator.connect() as sock:
            sock.sendall(b"GET:RC8:1:I:\r")
            assert sock.recv(64) == b"0,3,1\r"
    with pytest.raises(ConnectionRefusedError):  # stopped: nothing takes a connection
        simulator.connect().close()


def went_through(front: Front, line: str) -> list[bool]:
    """Whether each exchange of ``line`` was answered as it should be."""
    seq = front.engine.submit(line)
    front.until(lambda: seq in front.results, f"the answer to {line!r}")
    return [f.ok for f in front.results[seq].feedback if isinstance(f, Outcome)]


def test_only_a_served_engine_keeps_its_simulator_unlisted() -> None:
    """A served console's engine reaches its simulator over the pair, writes and
    reconnects included; elsewhere it listens on 127.0.0.1 for the user's other tools."""
    for where, port_given in ((Where.SERVED, False), (Where.CONSOLE, True)):
        engine = Engine(None, interval=0.05, timeout=1.0, where=where)
        engine.start()
        try:
            front = Front(engine)
            assert went_through(front, "put I 10 5") == [True]
            assert went_through(front, "send SIM:SET:garble_every=2") == [True]
            # Every second reply garbled: the session resets, and connects again for the next.
            answers = [went_through(front, "get I 10") for _ in range(4)]
            assert answers == [[True], [False], [True], [False]]
            status = front.status  # made when the target opened, before the first answer
            assert status is not None and (status.port != 0) is port_given
        finally:
            engine.stop()
