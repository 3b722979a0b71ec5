"""What the benchmarks share: the C programs, the responders, child processes that
measure themselves, CPU accounting and side-by-side rounds.

Every figure is a rate with the CPU it cost beside it: a child process measures its own
window (``time.process_time`` around the loop, all threads) and prints one JSON line
``{"requests": N, "seconds": S, "cpu": C}``; a C program's CPU is read from
``getrusage(RUSAGE_CHILDREN)`` around its run, a server's from ``/proc/PID/stat``.
Everything binds and connects to 127.0.0.1 only.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
HOST = "127.0.0.1"
REQUEST = b"GET:RC8:10:I:\r"
REPLY = b"0,3,123\r"

#: The Python responder, used only when there is no C compiler (and said loudly).
PYTHON_RESPONDER = r"""
import socket, threading
server = socket.socket()
server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
server.bind(("127.0.0.1", 0))
server.listen(128)
print(server.getsockname()[1], flush=True)
def serve(conn):
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    try:
        while data := conn.recv(65536):
            conn.sendall(b"0,3,123\r" * data.count(b"\r"))
    except OSError:
        pass
    conn.close()
while True:
    conn, _ = server.accept()
    threading.Thread(target=serve, args=(conn,), daemon=True).start()
"""


@dataclass(frozen=True)
class Run:
    """One measured window: requests completed, wall seconds, CPU seconds spent."""

    requests: float
    seconds: float
    cpu: float

    @property
    def rate(self) -> float:
        return self.requests / self.seconds if self.seconds > 0 else 0.0

    @property
    def cpu_us(self) -> float:
        """CPU microseconds per request."""
        return self.cpu / self.requests * 1e6 if self.requests else float("nan")


def report_run(requests: float, seconds: float, cpu: float, **extra: object) -> None:
    """What a measuring child prints last: one JSON line."""
    print(json.dumps({"requests": requests, "seconds": seconds, "cpu": cpu, **extra}), flush=True)


def child(script: str, *args: object, timeout: float = 600, cpu: int | None = None) -> dict:
    """Run ``benchmarks/SCRIPT ARGS`` in its own process (on CPU ``cpu`` alone, when
    given); its last stdout line, as JSON."""
    result = subprocess.run(
        [sys.executable, str(HERE / script), *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
        preexec_fn=pinned(cpu),
    )
    if result.returncode != 0:
        raise RuntimeError(f"{script} {args} failed:\n{result.stderr[-3000:]}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def child_run(script: str, *args: object, cpu: int | None = None) -> Run:
    out = child(script, *args, cpu=cpu)
    return Run(out["requests"], out["seconds"], out["cpu"])


def pinned(cpu: int | None) -> Callable[[], None] | None:
    """A ``preexec_fn`` that keeps the child (and its threads) on ``cpu``; None: anywhere."""
    if cpu is None:
        return None
    return lambda: os.sched_setaffinity(0, {cpu})


def placement_cpus(placement: str) -> tuple[int | None, int | None]:
    """(client CPU, server CPU) for a placement: ``same`` one CPU for both, ``apart``
    two CPUs, ``free`` wherever the scheduler puts them (None)."""
    if placement == "free" or not hasattr(os, "sched_setaffinity"):
        return None, None
    cpus = sorted(os.sched_getaffinity(0))
    if placement == "same" or len(cpus) < 2:
        return cpus[-1], cpus[-1]
    return cpus[-2], cpus[-1]


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def proc_cpu(pid: int) -> float:
    """User + system CPU seconds of a running process (Linux /proc); nan elsewhere."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return float("nan")
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


# ------------------------------------------------------------------ C programs


class CPrograms:
    """``rac_client`` and ``rac_responder`` built with ``cc -O2`` into a temp dir."""

    def __init__(self) -> None:
        self._dir = tempfile.TemporaryDirectory(prefix="rac-bench-")
        self.folder = Path(self._dir.name)
        self.error: str | None = None
        compiler = self.compiler = shutil.which("cc") or shutil.which("gcc")
        self.client: Path | None = None
        self.responder: Path | None = None
        if compiler is None:
            self.error = "no C compiler (cc or gcc) on PATH"
            return
        try:
            self.client = self._build(compiler, "rac_client")
            self.responder = self._build(compiler, "rac_responder")
        except subprocess.CalledProcessError as exc:
            self.client = self.responder = None
            self.error = f"the C programs did not compile: {exc.stderr or exc}"

    def _build(self, compiler: str, name: str) -> Path:
        binary = self.folder / name
        subprocess.run(
            [compiler, "-O2", "-o", str(binary), str(HERE / "c" / f"{name}.c")],
            check=True,
            capture_output=True,
            text=True,
        )
        return binary

    def build_optional(self, name: str) -> Path | None:
        """``c/NAME.c`` built, when the compiler and the file are there and it builds."""
        if self.compiler is None or not (HERE / "c" / f"{name}.c").exists():
            return None
        try:
            return self._build(self.compiler, name)
        except subprocess.CalledProcessError:
            return None

    def cleanup(self) -> None:
        self._dir.cleanup()


def run_c_client(
    binary: Path, port: int, sessions: int, seconds: float, cpu: int | None = None
) -> Run:
    """The C load client's rate; its CPU from getrusage of the reaped child."""
    before = children_cpu()
    out = subprocess.run(
        [str(binary), str(port), str(sessions), str(seconds)],
        capture_output=True,
        text=True,
        check=True,
        timeout=seconds + 60,
        preexec_fn=pinned(cpu),
    ).stdout
    rate = float(out)
    return Run(rate * seconds, seconds, children_cpu() - before)


class Server:
    """A responder child process that prints its port on its first line."""

    def __init__(self, command: list[str], cpu: int | None = None) -> None:
        self.process = subprocess.Popen(
            command, stdout=subprocess.PIPE, text=True, preexec_fn=pinned(cpu)
        )
        assert self.process.stdout is not None
        self.port = int(self.process.stdout.readline())
        self.pid = self.process.pid

    def cpu(self) -> float:
        return proc_cpu(self.pid)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(10)
        if self.process.stdout is not None:
            self.process.stdout.close()

    def __enter__(self) -> Server:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()


def start_responder(programs: CPrograms, cpu: int | None = None) -> tuple[Server, str]:
    """The C responder, or (loudly) the Python one; and which it is."""
    if programs.responder is not None:
        return Server([str(programs.responder), "0"], cpu), "C responder (cc -O2)"
    warn(
        f"{programs.error}: measuring against the PYTHON responder, which is far slower "
        "than a controller; the ratios below say little about the client"
    )
    return Server([sys.executable, "-c", PYTHON_RESPONDER], cpu), "PYTHON responder (no compiler)"


def warn(text: str) -> None:
    bar = "!" * 78
    print(f"{bar}\n!! WARNING: {text}\n{bar}", file=sys.stderr, flush=True)
    print(f"WARNING: {text}", flush=True)


# ------------------------------------------------------------------ rounds


def alternate(rounds: int, sides: dict[str, Callable[[], Run]]) -> dict[str, list[Run]]:
    """Each side once per round, in turn (the order turned each round), so noise on a
    shared machine hits every side alike."""
    results: dict[str, list[Run]] = {name: [] for name in sides}
    names = list(sides)
    for n in range(rounds):
        order = names if n % 2 == 0 else names[::-1]
        for name in order:
            results[name].append(sides[name]())
    return results


def ratio(results: dict[str, list[Run]], top: str, bottom: str) -> float:
    """The median of the per-round ratios of two sides' rates."""
    pairs = zip(results[top], results[bottom], strict=True)
    return statistics.median(a.rate / b.rate for a, b in pairs)


def median_rate(runs: list[Run]) -> float:
    return statistics.median(run.rate for run in runs)


def median_cpu_us(runs: list[Run]) -> float:
    return statistics.median(run.cpu_us for run in runs)
