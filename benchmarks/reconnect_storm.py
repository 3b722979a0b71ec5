"""Connections per second a console makes to a controller that drops every connection.

    python benchmarks/reconnect_storm.py [--seconds 10] [--rows 50]

A server here accepts, reads one request and closes; the console's engine
(:class:`rac_console.engine.Engine`, on its own thread, its outbox drained every 50 ms
as the console and the REPL do) watches ROWS variables at interval 0.05 s for SECONDS.
It prints the figure, with the engine process's CPU per connection; it asserts nothing.
"""

from __future__ import annotations

import argparse
import contextlib
import resource
import socket
import threading
import time

from rac_console.engine import Engine


def drop_server() -> tuple[socket.socket, list[int]]:
    sock = socket.create_server(("127.0.0.1", 0))
    accepted = [0]

    def serve(conn: socket.socket) -> None:
        with conn, contextlib.suppress(OSError):
            conn.recv(4096)

    def accept() -> None:
        while True:
            try:
                conn, _ = sock.accept()
            except OSError:
                return
            accepted[0] += 1
            threading.Thread(target=serve, args=(conn,), daemon=True).start()

    threading.Thread(target=accept, daemon=True).start()
    return sock, accepted


def cpu_now() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def measure(seconds: float, rows: int) -> tuple[float, float]:
    """Connections/s the engine made, and this process's CPU µs per connection."""
    sock, accepted = drop_server()
    engine = Engine("127.0.0.1", sock.getsockname()[1], timeout=1.0, interval=0.05)
    engine.start()
    engine.submit(f"watch I 0-{rows - 1}")
    before, cpu, started = accepted[0], cpu_now(), time.perf_counter()
    while time.perf_counter() - started < seconds:
        time.sleep(0.05)
        engine.outbox.drain()  # as a front end does
    count = accepted[0] - before
    elapsed, cpu = time.perf_counter() - started, cpu_now() - cpu
    engine.stop()
    sock.close()
    return count / elapsed, cpu / max(count, 1) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--rows", type=int, default=50)
    args = parser.parse_args()
    rate, cpu_us = measure(args.seconds, args.rows)
    print(
        f"{rate:.1f} connections/s over {args.seconds:g} s, {args.rows} watched variables; "
        f"{cpu_us:,.0f} µs CPU per connection (engine process, server threads included)"
    )


if __name__ == "__main__":
    main()
