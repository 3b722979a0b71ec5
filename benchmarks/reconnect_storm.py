"""Connections per second a console makes to a controller that drops every connection.

    python benchmarks/reconnect_storm.py [--seconds 10] [--rows 50]

A server here accepts, reads one request and closes; the console's engine (headless,
as the console and the REPL run it) watches ROWS variables at interval 0.05 s for
SECONDS. It prints the figure; it asserts nothing.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import socket
import threading
import time

from rac_console.core import ConsoleCore


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


async def measure(seconds: float, rows: int) -> float:
    sock, accepted = drop_server()
    core = ConsoleCore("127.0.0.1", sock.getsockname()[1], timeout=1.0, interval=0.05)
    await core.start()
    await core.handle_line(f"watch I 0-{rows - 1}")
    started = time.perf_counter()
    await asyncio.sleep(seconds)
    count = accepted[0]
    elapsed = time.perf_counter() - started
    await core.stop()
    sock.close()
    return count / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--rows", type=int, default=50)
    args = parser.parse_args()
    rate = asyncio.run(measure(args.seconds, args.rows))
    print(f"{rate:.1f} connections/s over {args.seconds:g} s, {args.rows} watched variables")


if __name__ == "__main__":
    main()
