"""What a flood of refused requests costs ``rac-console serve``, and its operator.

    python benchmarks/serve_stderr.py [--seconds 10] [--clients 8]

Starts ``rac-console serve`` (``tests/support/serving.py``), opens one session as a
browser does, then has ``--clients`` threads send refused requests back to back for
``--seconds`` (no cookie: 403; a foreign Host: 421; a malformed Content-Length and a
malformed header: aiohttp's 400). Two rounds: serve's stderr read as fast as it comes,
then read at 200 bytes a second (a terminal or an ssh link that does not keep up), the
operator typing ``get I 1`` halfway through. Prints, for each: the requests answered,
the lines and bytes serve wrote on stderr, its CPU (``/proc``), and how long the get
took (up to 60 s). Run it from another checkout (``PYTHONPATH=OLD``) to measure that
checkout's serve.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import socket
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the tests' way of driving serve: tests.support

from tests.support.drivers import Running  # noqa: E402
from tests.support.serving import Served, open_console, start_serve  # noqa: E402

REFUSED = [
    b"GET / HTTP/1.1\r\nHost: HOST\r\nConnection: close\r\n\r\n",
    b"GET / HTTP/1.1\r\nHost: evil.example:PORT\r\nConnection: close\r\n\r\n",
    b"GET / HTTP/1.1\r\nHost: HOST\r\nContent-Length: x\r\n\r\n",
    b"GET / HTTP/1.1\r\nHo st: x\r\nHost: HOST\r\n\r\n",
]


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def send(served: Served, raw: bytes) -> None:
    data = raw.replace(b"HOST", served.host.encode()).replace(b"PORT", str(served.port).encode())
    with socket.create_connection(("127.0.0.1", served.port), timeout=60) as sock:
        sock.sendall(data)
        while sock.recv(65536):
            pass


def measure(env: dict[str, str], seconds: float, clients: int, err_rate: int | None) -> str:
    running: list[Running] = []
    try:
        served = start_serve(env, running, err_rate=err_rate)
        console = open_console(served)
        console.until("connected")
        pid = served.running.process.pid
        stop = threading.Event()
        answered = [0] * clients

        def flood(n: int) -> None:
            while not stop.is_set():
                with contextlib.suppress(OSError):
                    send(served, REFUSED[n % len(REFUSED)])
                    answered[n] += 1

        threads = [threading.Thread(target=flood, args=(n,), daemon=True) for n in range(clients)]
        cpu, start = cpu_seconds(pid), time.monotonic()
        for thread in threads:
            thread.start()
        time.sleep(seconds / 2)
        typed = time.monotonic()
        console.type_line("get I 1")
        try:
            console.until("I1 = 1", deadline=60)
            got = f"{time.monotonic() - typed:.2f} s"
        except AssertionError:
            got = "no answer in 60 s"
        time.sleep(max(0.0, start + seconds - time.monotonic()))
        stop.set()
        elapsed = time.monotonic() - start
        used = cpu_seconds(pid) - cpu
        lines = list(served.running.err)
        size = sum(len(line.encode()) + 1 for line in lines)
        for thread in threads:
            thread.join(60)
        console.close()
        return (
            f"{sum(answered) / elapsed:7.0f} refused/s  stderr {len(lines) / elapsed:8.1f} "
            f"lines/s {size / elapsed / 1024:8.1f} KiB/s (as read)  serve CPU "
            f"{100 * used / elapsed:3.0f} %  get {got}"
        )
    finally:
        for run in running:
            run.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--clients", type=int, default=8)
    args = parser.parse_args()
    env = dict(os.environ) | {"PYTHONIOENCODING": "utf-8"}
    for rate, name in ((None, "stderr read at once"), (200, "stderr read at 200 B/s")):
        print(f"{name:24} {measure(env, args.seconds, args.clients, rate)}", flush=True)


if __name__ == "__main__":
    main()
