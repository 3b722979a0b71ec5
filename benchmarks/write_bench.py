"""What read-back costs: writes a second, side by side against the C responder.

    python benchmarks/write_bench.py [--count N] [--rounds R]

A bare socket loop sending the PUT alone (the floor), the client's write with
``--no-verify`` (the PUT alone) and the verified write (GET, PUT, GET: three round trips,
so about a third of the rate is what it should cost). Ratios within a round are what to
read: absolute figures swing on a shared machine.
"""

from __future__ import annotations

import argparse
import socket
import time

from bench_common import CPrograms, start_responder

from rac_console.commands.exchange_parsers import parse_put
from rac_console.commands.policy import WritePolicy
from rac_console.commands.routing import WriteTrait
from rac_console.engine.exchange.gate import WriteGate
from rac_console.session import Session

PUT = parse_put("I 10 5")


def bare(port: int, count: int) -> float:
    """PUTs a second over a plain socket: send, read to CR."""
    with socket.create_connection(("127.0.0.1", port)) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        started = time.perf_counter()
        for _ in range(count):
            sock.sendall(PUT.request.data)
            reply = b""
            while not reply.endswith(b"\r"):
                reply += sock.recv(256)
        return count / (time.perf_counter() - started)


def client(port: int, count: int, verify: bool) -> float:
    """Writes a second through the write gate (what put, run, the console and the library use)."""
    session = Session("127.0.0.1", port, timeout=2)
    gate = WriteGate(WritePolicy(), WriteTrait.ALWAYS, "put", verify=verify)
    try:
        started = time.perf_counter()
        for _ in range(count):
            gate.exchange(session, PUT)
        return count / (time.perf_counter() - started)
    finally:
        session.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=3000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    programs = CPrograms()
    server, what = start_responder(programs)
    print(f"against the {what}, {args.count} writes a side")
    try:
        for n in range(args.rounds):
            floor = bare(server.port, args.count)
            alone = client(server.port, args.count, verify=False)
            verified = client(server.port, args.count, verify=True)
            print(
                f"round {n}: bare PUT {floor:,.0f}/s  --no-verify {alone:,.0f}/s "
                f"({alone / floor:.2f}x bare)  verified {verified:,.0f}/s "
                f"({verified / floor:.2f}x bare, {verified / alone:.2f}x --no-verify)"
            )
    finally:
        server.stop()
        programs.cleanup()


if __name__ == "__main__":
    main()
