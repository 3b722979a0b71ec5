"""The library's cost per ``get``: ``rc.get("I", 10)`` against ``Session.get`` beside a bare
socket loop, against the C responder.

    python benchmarks/library_get.py [--rounds 15] [--requests 5000] [--placement same]

One process holds every side's connection (each its own) to the C responder
(``benchmarks/c/rac_responder.c``, ``cc -O2``; the Python one, loudly, without a
compiler); with ``--placement same`` (the default, as ``floor.py``) it and the responder
share one CPU, so a request costs the client's CPU, the responder's and two switches.
Each round asks every side for REQUESTS gets, in turn (the order turned each round).

Sides:

- ``bare``: a blocking socket, ``sendall``, ``recv`` until CR: the least Python can do;
- ``session``: ``Session.get(kind_of("I"), 10)``, the session below every front end;
- ``library``: ``rac.connect(...).get("I", 10)``: the value checked and typed, the
  console's write path's read, under the connection's lock;
- ``aio``: ``await rc.get("I", 10)`` of ``rac.aio``, one after another: the library plus a
  hop to the connection's thread and back for every get.

Printed: each side's median rate and wall and CPU microseconds per get, and the library's
overhead per get over ``Session.get`` (the median of the per-round differences).
"""

from __future__ import annotations

import argparse
import asyncio
import socket
import statistics
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_common import (  # noqa: E402
    HOST,
    REQUEST,
    CPrograms,
    Run,
    alternate,
    median_cpu_us,
    median_rate,
    pinned,
    placement_cpus,
    start_responder,
)

SIDES = ("bare", "session", "library", "aio")


def measured(count: int, work: Callable[[int], None]) -> Run:
    """``work(count)`` timed: wall and CPU (this process, all threads)."""
    cpu, started = time.process_time(), time.perf_counter()
    work(count)
    return Run(count, time.perf_counter() - started, time.process_time() - cpu)


class Sides:
    """Every side's connection to the responder at ``port``, opened once."""

    def __init__(self, port: int) -> None:
        import rac_console as rac
        from rac_console.protocol import kind_of
        from rac_console.session import Session

        self._sock = socket.create_connection((HOST, port))
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._session = Session(HOST, port)
        self._kind = kind_of("I")
        self._rc = rac.connect(HOST, port=port)
        self._loop = asyncio.new_event_loop()
        self._aio = self._loop.run_until_complete(rac.aio.connect(HOST, port=port).open())
        for side in SIDES:  # every connection open and warm before the first round
            getattr(self, side)(50)

    def bare(self, count: int) -> None:
        sock, request = self._sock, REQUEST
        for _ in range(count):
            sock.sendall(request)
            data = sock.recv(256)
            while not data.endswith(b"\r"):
                data += sock.recv(256)

    def session(self, count: int) -> None:
        get, kind = self._session.get, self._kind
        for _ in range(count):
            get(kind, 10)

    def library(self, count: int) -> None:
        get = self._rc.get
        for _ in range(count):
            get("I", 10)

    def aio(self, count: int) -> None:
        rc = self._aio

        async def gets() -> None:
            for _ in range(count):
                await rc.get("I", 10)

        self._loop.run_until_complete(gets())

    def close(self) -> None:
        self._loop.run_until_complete(self._aio.close())
        self._loop.close()
        self._rc.close()
        self._session.close()
        self._sock.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--requests", type=int, default=5000)
    parser.add_argument("--placement", choices=("same", "apart", "free"), default="same")
    args = parser.parse_args()
    client_cpu, server_cpu = placement_cpus(args.placement)
    programs = CPrograms()
    responder, kind = start_responder(programs, server_cpu)
    try:
        keep_to_cpu = pinned(client_cpu)
        if keep_to_cpu is not None:
            keep_to_cpu()
        sides = Sides(responder.port)
        try:
            results = alternate(
                args.rounds,
                {name: partial(measured, args.requests, getattr(sides, name)) for name in SIDES},
            )
        finally:
            sides.close()
    finally:
        responder.stop()
        programs.cleanup()
    report(results, kind, args)


def report(results: dict[str, list[Run]], kind: str, args: argparse.Namespace) -> None:
    print(
        f"{args.requests} gets a side a round, {args.rounds} rounds, against the {kind}, "
        f"placement {args.placement}; medians"
    )
    print(f"{'side':<9} {'gets/s':>9} {'µs/get':>8} {'CPU µs/get':>11}")
    for name in SIDES:
        runs = results[name]
        rate = median_rate(runs)
        print(f"{name:<9} {rate:>9,.0f} {1e6 / rate:>8.1f} {median_cpu_us(runs):>11.1f}")
    for side in ("library", "aio"):
        extra = statistics.median(
            (a.seconds - b.seconds) / a.requests * 1e6
            for a, b in zip(results[side], results["session"], strict=True)
        )
        share = statistics.median(
            b.rate / a.rate for a, b in zip(results[side], results["session"], strict=True)
        )
        print(
            f"{side} over Session.get: +{extra:.1f} µs a get ({share:.2f}x the time of Session.get)"
        )


if __name__ == "__main__":
    main()
