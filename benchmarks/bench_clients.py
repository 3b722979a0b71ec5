"""The measuring clients, each run by ``run.py`` in a process of its own.

    python benchmarks/bench_clients.py bare    PORT SECONDS [WARMUP]
    python benchmarks/bench_clients.py session PORT SECONDS [WARMUP]
    python benchmarks/bench_clients.py engine  PORT SECONDS [WARMUP]
    python benchmarks/bench_clients.py profile PORT SECONDS OUT.prof
    python benchmarks/bench_clients.py multi   PORT SECONDS SESSIONS

Each prints one JSON line last: ``{"requests", "seconds", "cpu"}`` over the measured
window only (after WARMUP seconds), CPU being this process's user + system time from
``getrusage(RUSAGE_SELF)`` (every thread). Requests are ``GET:RC8:10:I:`` (``bare``,
``session``, ``multi``) or the polls of 100 watched variables I0..I99 (``engine``).

- ``bare``: a blocking socket, ``sendall``, ``recv``, split on CR: the least Python can do.
- ``session``: :class:`rac_console.session.Session` ``.get(kind_of("I"), 10)`` in a loop.
- ``engine``: an :class:`rac_console.engine.Engine` at interval 0 watching I 0-99, its
  outbox drained every 50 ms as a front end does; requests are the poll frames sent
  (``direction == "tx"``, ``poll=True``) found in the drained batches.
- ``profile``: the ``session`` loop under cProfile, the stats written to OUT.prof.
- ``multi``: SESSIONS connections, one request in flight on each (selectors): the
  stand-in for the C load client when there is no compiler.
"""

from __future__ import annotations

import cProfile
import resource
import selectors
import socket
import sys
import time
from collections.abc import Callable

from bench_common import HOST, REQUEST, report_run

BATCH = 100
DRAIN_EVERY = 0.05


def cpu_now() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def timed(batch: Callable[[], None], seconds: float, warmup: float) -> tuple[int, float, float]:
    """Run ``batch`` (BATCH requests) for ``warmup`` s, then for ``seconds`` s, measured."""
    perf = time.perf_counter
    end = perf() + warmup
    while perf() < end:
        batch()
    count = 0
    cpu, started = cpu_now(), perf()
    end = started + seconds
    while perf() < end:
        batch()
        count += BATCH
    elapsed = perf() - started
    return count, elapsed, cpu_now() - cpu


def bare(port: int, seconds: float, warmup: float) -> None:
    sock = socket.create_connection((HOST, port))
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    state = [b""]

    def batch() -> None:
        sendall, recv, request = sock.sendall, sock.recv, REQUEST
        buffer = state[0]
        for _ in range(BATCH):
            sendall(request)
            while b"\r" not in buffer:
                buffer += recv(4096)
            _line, _, buffer = buffer.partition(b"\r")
        state[0] = buffer

    report_run(*timed(batch, seconds, warmup))
    sock.close()


def session_loop(port: int) -> tuple[Callable[[], None], Callable[[], None]]:
    from rac_console.protocol import kind_of
    from rac_console.session import Session

    session = Session(HOST, port, timeout=2.0)
    kind, get = kind_of("I"), session.get

    def batch() -> None:
        get_, kind_ = get, kind
        for _ in range(BATCH):
            get_(kind_, 10)

    return batch, session.close


def session(port: int, seconds: float, warmup: float) -> None:
    batch, close = session_loop(port)
    report_run(*timed(batch, seconds, warmup))
    close()


def profile(port: int, seconds: float, out: str) -> None:
    batch, close = session_loop(port)
    batch()  # connected before the profile starts
    profiler = cProfile.Profile()
    count, elapsed, cpu = profiler.runcall(timed, batch, seconds, 0.0)
    profiler.dump_stats(out)
    close()
    report_run(count, elapsed, cpu)


def engine(port: int, seconds: float, warmup: float) -> None:
    from rac_console.engine import Alert, Engine, Note
    from rac_console.session import Frame

    eng = Engine(HOST, port, timeout=2.0, interval=0.0)
    eng.start()
    eng.submit("watch I 0-99")
    outbox = eng.outbox
    notes = 0

    def drain() -> int:
        """Take a batch as a front end does; the poll requests sent in it."""
        nonlocal notes
        polls = 0
        for event in outbox.drain().events:
            if type(event) is Frame:
                if event.poll and event.direction == "tx":
                    polls += 1
            elif isinstance(event, Note | Alert):
                notes += 1
        return polls

    perf = time.perf_counter
    end = perf() + max(warmup, 0.1)
    while perf() < end or not drain():  # warm: until polls flow
        time.sleep(DRAIN_EVERY)
    drain()
    polls, cpu, started = 0, cpu_now(), perf()
    while perf() - started < seconds:
        time.sleep(DRAIN_EVERY)
        polls += drain()
    elapsed, cpu = perf() - started, cpu_now() - cpu
    eng.stop()
    report_run(polls, elapsed, cpu, notes=notes)


def multi(port: int, seconds: float, sessions: int) -> None:
    selector = selectors.DefaultSelector()
    socks = []
    for _ in range(sessions):
        sock = socket.create_connection((HOST, port))
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.setblocking(False)
        selector.register(sock, selectors.EVENT_READ)
        socks.append(sock)
        sock.send(REQUEST)
    count, cpu, started = 0, cpu_now(), time.perf_counter()
    while time.perf_counter() - started < seconds:
        for key, _ in selector.select(0.1):
            sock = key.fileobj
            assert isinstance(sock, socket.socket)
            replies = sock.recv(4096).count(b"\r")
            count += replies
            if replies:
                sock.send(REQUEST)
    report_run(count, time.perf_counter() - started, cpu_now() - cpu)
    for sock in socks:
        sock.close()


def main(argv: list[str]) -> None:
    mode, port, seconds = argv[0], int(argv[1]), float(argv[2])
    if mode == "profile":
        profile(port, seconds, argv[3])
    elif mode == "multi":
        multi(port, seconds, int(argv[3]))
    else:
        warmup = float(argv[3]) if len(argv) > 3 else 0.3
        {"bare": bare, "session": session, "engine": engine}[mode](port, seconds, warmup)


if __name__ == "__main__":
    main(sys.argv[1:])
