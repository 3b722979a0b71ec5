"""The client against its floor: every path of one request, side by side in one run.

    python benchmarks/floor.py [--rounds 30] [--requests 2000] [--old DIR] [--callgrind]

Against the C responder (``benchmarks/c/rac_responder.c``, ``cc -O2``), one request in
flight, the responder and every client pinned to one CPU (a request then costs the
client's CPU, the responder's and two switches: the rates compare what each path
costs). One worker process per package (this checkout's, and with ``--old DIR`` the
package in DIR) holds every side's connection; each round asks every side of every
package for REQUESTS requests, in turn (the order turned each round). A figure is the
median of the per-round ratios to the same worker's bare loop, with the quartiles.

Sides:

- ``bare``: a blocking socket, ``sendall``, ``recv`` until CR: the least Python can do;
- ``get``: ``Session.get(kind_of("I"), 10)``; ``exchange``: ``Session.exchange`` of a
  request made once; ``latency``: ``measure_latency`` (the ``latency`` command);
- ``execute``: ``execute(session, Get(I10))``, what the CLI's ``get`` and ``run`` do;
- ``engine``: an engine watching I 0-99 at interval 0 with nobody showing its poll
  frames (the REPL without ``frames on``, a CLI watch); polls timed between the first
  and the last poll cycle of the round (``Cycle.monotonic``), CPU of the whole process.

With ``--callgrind`` each side of each package also runs 2,000 requests under
``valgrind --tool=callgrind`` once: instructions per request, which do not swing with
the machine's load (the bare loop's subtracted out of nothing: all are shown whole).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

HOST = "127.0.0.1"
REQUEST = b"GET:RC8:10:I:\r"
SIDES = ("bare", "get", "exchange", "latency", "execute", "engine")
#: (side, target, what the target is a ratio of): rate, then CPU per request.
TARGETS = {
    "get": ("bare", 0.85, 1.25),
    "exchange": ("bare", 0.85, 1.25),
    "latency": ("bare", 0.85, 1.25),
    "execute": ("bare", 0.75, None),
    "engine": ("get", 0.8, None),
}


# ------------------------------------------------------------------ the worker


def cpu_now() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


class Worker:
    """Every side over its own connection, in this process (one package)."""

    def __init__(self, port: int) -> None:
        from rac_console.commands.language import Get, VarRef
        from rac_console.engine.exchange.execute import execute, measure_latency
        from rac_console.protocol import kind_of
        from rac_console.session import Session

        self.port = port
        kind = kind_of("I")
        var = VarRef(kind, 10)
        self.sock = socket.create_connection((HOST, port))
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.buffer = b""
        sessions = {name: Session(HOST, port, timeout=2.0) for name in SIDES[1:5]}
        request = Get(var).request
        get_, exchange_ = sessions["get"].get, sessions["exchange"].exchange
        latency_session, execute_session = sessions["latency"], sessions["execute"]

        def get(count: int) -> None:
            for _ in range(count):
                get_(kind, 10)

        def exchange(count: int) -> None:
            for _ in range(count):
                exchange_(request)

        def latency(count: int) -> None:
            measure_latency(latency_session, var, count, 0.0)

        def run_execute(count: int) -> None:
            for _ in range(count):
                execute(execute_session, Get(var))

        self.sides: dict[str, Callable[[int], None]] = {
            "bare": self.bare,
            "get": get,
            "exchange": exchange,
            "latency": latency,
            "execute": run_execute,
        }
        for run in self.sides.values():
            run(200)  # connected and warm
        self.engine = self._engine()

    def bare(self, count: int) -> None:
        sendall, recv, buffer = self.sock.sendall, self.sock.recv, self.buffer
        for _ in range(count):
            sendall(REQUEST)
            while b"\r" not in buffer:
                buffer += recv(4096)
            _line, _, buffer = buffer.partition(b"\r")
        self.buffer = buffer

    def _engine(self) -> object:
        from rac_console.engine import Engine

        engine = Engine(HOST, self.port, timeout=2.0, interval=0.0, cycles=True)
        if hasattr(engine, "set_poll_frames"):
            engine.set_poll_frames(False)  # nobody shows them
        engine.start()
        self._submit_and_wait(engine, "watch I 0-99")
        self._submit_and_wait(engine, "pause")
        return engine

    @staticmethod
    def _submit_and_wait(engine: object, line: str) -> None:
        from rac_console.engine import Result

        seq = engine.submit(line)  # type: ignore[attr-defined]
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            for event in engine.outbox.drain().events:  # type: ignore[attr-defined]
                if isinstance(event, Result) and event.seq == seq:
                    return
            time.sleep(0.005)
        raise RuntimeError(f"no result for {line!r}")

    def run_engine(self, count: int) -> tuple[float, float, int]:
        """Polls for about ``count`` requests: (seconds, CPU, polls) between the first
        poll cycle's end and the last's."""
        from rac_console.engine import Cycle

        engine = self.engine
        cycles_wanted = max(2, count // 100 + 1)
        stamps: list[tuple[float, float]] = []  # (Cycle.monotonic, CPU when drained)
        self._submit_and_wait(engine, "resume")
        deadline = time.monotonic() + 60
        while len(stamps) < cycles_wanted and time.monotonic() < deadline:
            time.sleep(0.002)
            for event in engine.outbox.drain().events:  # type: ignore[attr-defined]
                if isinstance(event, Cycle) and len(event.samples) == 100:
                    stamps.append((event.monotonic, cpu_now()))
        self._submit_and_wait(engine, "pause")
        (first, cpu_first), (last, cpu_last) = stamps[0], stamps[-1]
        polls = (len(stamps) - 1) * 100
        return last - first, cpu_last - cpu_first, polls

    def run(self, side: str, count: int) -> dict[str, float]:
        if side == "engine":
            seconds, cpu, done = self.run_engine(count)
            return {"seconds": seconds, "cpu": cpu, "requests": done}
        run = self.sides[side]
        cpu, started = cpu_now(), time.perf_counter()
        run(count)
        return {
            "seconds": time.perf_counter() - started,
            "cpu": cpu_now() - cpu,
            "requests": count,
        }


def worker_main(port: int) -> None:
    import rac_console

    worker = Worker(port)
    print("ready", rac_console.__file__, flush=True)
    for line in sys.stdin:
        side, count = line.split()
        print(json.dumps(worker.run(side, int(count))), flush=True)


def callgrind_main(port: int, side: str, count: int) -> None:
    """One side, ``count`` requests after the worker is set up, then exit: run twice
    under callgrind with two counts, the difference is what the extra requests cost."""
    worker = Worker(port)
    worker.run(side, count)
    os._exit(0)


# ------------------------------------------------------------------ the parent


class Child:
    def __init__(self, package: Path | None, port: int, cpu: int | None) -> None:
        env = dict(os.environ)
        if package is not None:
            env["PYTHONPATH"] = str(package) + os.pathsep + env.get("PYTHONPATH", "")
        self.process = subprocess.Popen(
            [sys.executable, __file__, "--worker", str(port)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env,
            cwd=str(package) if package is not None else None,
            preexec_fn=(lambda: os.sched_setaffinity(0, {cpu})) if cpu is not None else None,
        )
        assert self.process.stdout is not None
        ready = self.process.stdout.readline().split()
        if not ready or ready[0] != "ready":
            raise RuntimeError(f"the worker did not start: {ready!r}")
        self.package = ready[1] if len(ready) > 1 else "?"

    def run(self, side: str, count: int) -> dict[str, float]:
        assert self.process.stdin is not None and self.process.stdout is not None
        self.process.stdin.write(f"{side} {count}\n")
        self.process.stdin.flush()
        return json.loads(self.process.stdout.readline())  # type: ignore[no-any-return]

    def stop(self) -> None:
        if self.process.stdin is not None:
            self.process.stdin.close()
        self.process.wait(20)


def quartiles(values: list[float]) -> tuple[float, float, float]:
    if len(values) < 4:
        middle = statistics.median(values)
        return middle, min(values), max(values)
    q1, q2, q3 = statistics.quantiles(values, n=4)
    return q2, q1, q3


def callgrind_counts(package: Path | None, port: int, count: int) -> dict[str, float]:
    """Instructions per request for each side: callgrind's totals for ``count`` and for
    ``count`` more requests after the same set-up, the difference divided by ``count``
    (the set-up, the interpreter's start and the warm-up cancel out)."""
    env = dict(os.environ)
    if package is not None:
        env["PYTHONPATH"] = str(package) + os.pathsep + env.get("PYTHONPATH", "")

    def total(side: str, requests: int) -> int:
        with tempfile.TemporaryDirectory() as folder:
            out = Path(folder) / "callgrind.out"
            subprocess.run(
                ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                 sys.executable, __file__, "--callgrind-side", side, str(port), str(requests)],
                env=env,
                cwd=str(package) if package is not None else None,
                capture_output=True,
                timeout=1800,
            )  # fmt: skip
            found = 0
            for path in Path(folder).glob("callgrind.out*"):
                match = re.search(r"^(?:summary|totals):\s+(\d+)", path.read_text(), re.M)
                if match:
                    found += int(match.group(1))
            return found

    counts: dict[str, float] = {}
    for side in SIDES:
        small, large = total(side, count), total(side, 2 * count)
        extra = count if side != "engine" else (2 * count // 100 - count // 100) * 100
        counts[side] = (large - small) / extra if small and large else float("nan")
    return counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=30)
    parser.add_argument("--requests", type=int, default=2000)
    parser.add_argument("--old", type=Path, help="a checkout whose package to measure beside")
    parser.add_argument("--callgrind", action="store_true")
    parser.add_argument("--json", type=Path, help="write the figures here too")
    args = parser.parse_args()

    from bench_common import CPrograms, start_responder

    programs = CPrograms()
    cpus = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    cpu = cpus[-1] if cpus else None
    responder, kind = start_responder(programs, cpu)
    packages: dict[str, Path | None] = {"new": None}
    if args.old is not None:
        packages["old"] = args.old.resolve()
    children = {name: Child(path, responder.port, cpu) for name, path in packages.items()}
    for name, child in children.items():
        print(f"# {name}: {Path(child.package).parent}")
    runs: dict[str, dict[str, list[dict[str, float]]]] = {
        name: {side: [] for side in SIDES} for name in packages
    }
    try:
        order = [(name, side) for name in packages for side in SIDES]
        for n in range(args.rounds):
            for name, side in order if n % 2 == 0 else order[::-1]:
                runs[name][side].append(children[name].run(side, args.requests))
        counts = (
            {name: callgrind_counts(path, responder.port, 2000) for name, path in packages.items()}
            if args.callgrind and shutil.which("valgrind")
            else {}
        )
    finally:
        for child in children.values():
            child.stop()
        responder.stop()
    figures = report(runs, counts, args, kind, cpu)
    if args.json is not None:
        args.json.write_text(json.dumps(figures, indent=2) + "\n", encoding="utf-8")


def report(
    runs: dict[str, dict[str, list[dict[str, float]]]],
    counts: dict[str, dict[str, float]],
    args: argparse.Namespace,
    kind: str,
    cpu: int | None,
) -> dict[str, object]:
    print(
        f"# {args.rounds} rounds of {args.requests} requests per side, against the {kind}, "
        f"client and responder on CPU {cpu}; medians [quartiles] of per-round ratios"
    )
    figures: dict[str, object] = {}
    header = f"{'side':<10}"
    for name in runs:
        header += f" | {name + ' rate/bare':>24} {name + ' CPU/bare':>22} {'req/s':>8}"
    header += " | target"
    print(header)
    for side in SIDES:
        line = f"{side:<10}"
        for name, sides in runs.items():
            rate = [
                (r["requests"] / r["seconds"]) / (b["requests"] / b["seconds"])
                for r, b in zip(sides[side], sides["bare"], strict=True)
            ]
            cpu_ratio = [
                (r["cpu"] / r["requests"]) / (b["cpu"] / b["requests"])
                for r, b in zip(sides[side], sides["bare"], strict=True)
                if b["cpu"] > 0 and r["requests"]
            ]
            per_s = statistics.median(r["requests"] / r["seconds"] for r in sides[side])
            m, lo, hi = quartiles(rate)
            c, clo, chi = quartiles(cpu_ratio) if cpu_ratio else (float("nan"),) * 3
            line += f" | {m:>6.2f} [{lo:.2f}-{hi:.2f}]{'':>8} "
            line += f"{c:>6.2f} [{clo:.2f}-{chi:.2f}]{'':>6} {per_s:>8,.0f}"
            figures[f"{name}.{side}.rate_to_bare"] = m
            figures[f"{name}.{side}.cpu_to_bare"] = c
            figures[f"{name}.{side}.per_s"] = per_s
        target = TARGETS.get(side)
        if target is not None:
            of, rate_goal, cpu_goal = target
            goal = f"rate >= {rate_goal}x {of}" + (f", CPU <= {cpu_goal}x" if cpu_goal else "")
            new = figures["new." + side + ".rate_to_bare"]
            base = figures["new." + of + ".rate_to_bare"]
            assert isinstance(new, float) and isinstance(base, float)
            met = new / base >= rate_goal
            if cpu_goal is not None:
                cpu_new = figures["new." + side + ".cpu_to_bare"]
                assert isinstance(cpu_new, float)
                met = met and cpu_new <= cpu_goal
            line += f" | {goal}: {'met' if met else 'NOT met'} ({new / base:.2f}x {of})"
        print(line)
    if counts:
        print("\ninstructions per request (callgrind, 2,000 requests; engine: per poll)")
        print(f"{'side':<10}" + "".join(f" {name:>12}" for name in counts))
        for side in SIDES:
            print(f"{side:<10}" + "".join(f" {c[side]:>12,.0f}" for c in counts.values()))
            for name, c in counts.items():
                figures[f"{name}.{side}.instructions"] = c[side]
    return figures


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--worker":
        worker_main(int(sys.argv[2]))
    elif len(sys.argv) > 4 and sys.argv[1] == "--callgrind-side":
        callgrind_main(int(sys.argv[3]), sys.argv[2], int(sys.argv[4]))
    else:
        main()
