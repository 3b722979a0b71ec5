"""The simulator against abusive clients: what each kind of abuse costs it.

    python benchmarks/sim_abuse.py [--hostile 2000] [--deaf 150] [--idle 1100]
                                   [--fd-limit 1024] [--only SECTION ...] [--json FILE]

The simulator runs in its own process, ``python -m rac_console sim --port 0``, started
from a scratch directory so that PYTHONPATH decides which package it is (run it with
``PYTHONPATH=/tmp/simold`` to measure an older copy). Sections:

  - noise:  HOSTILE short connections (junk, a partial line, 50 pipelined requests then
            close without reading, a half-close after a request), each kind in turn; the
            lines the simulator wrote on stderr, and whether it still answers afterwards
            when its stderr is a pipe nobody reads.
  - deaf:   DEAF clients that send requests and never read a reply, until the kernel
            will take no more; the simulator's RSS (VmRSS, and the peak VmHWM), and the
            round trips of a normal client meanwhile (median, max).
  - fds:    the simulator under ``RLIMIT_NOFILE`` = FD_LIMIT (POSIX only) and IDLE idle
            connections: its open fds, how long a normal client waits for an answer,
            stderr lines, and what became of the idle connections.
  - control: ``SIM:SET:delay_ms=inf`` and whether a GET is answered after it.

It prints figures and asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import selectors
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from sim_harness import HOST, SimulatorProcess, ask, hostile

try:
    import resource
except ImportError:  # not POSIX: the fds section is skipped
    resource = None  # type: ignore[assignment]

SECTIONS = ("noise", "deaf", "fds", "control")


# ------------------------------------------------------------------- helpers


def wait_for(predicate: Callable[[], bool], timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.05)
    return predicate()


# --------------------------------------------------------------------- noise


def storm(port: int, count: int, batch: int = 100) -> float:
    started = time.perf_counter()
    threads = 8
    for first in range(0, count, batch):
        numbers = list(range(first, min(first + batch, count)))
        workers = [
            threading.Thread(target=lambda ns=numbers[w::threads]: [hostile(port, k) for k in ns])
            for w in range(threads)
        ]
        for worker in workers:
            worker.start()
        for worker in workers:
            worker.join(30)
    return time.perf_counter() - started


def noise_section(count: int) -> dict[str, Any]:
    out: dict[str, Any] = {}
    with SimulatorProcess() as sim:
        out["storm_seconds"] = round(storm(sim.port, count), 2)
        out["answered_after"] = ask(sim.port, 10) is not None
        time.sleep(1.0)  # let the last writes fail and any summary line come out
        text = sim.stderr()
        out["stderr_lines"] = len(text.splitlines())
        out["stderr_bytes"] = len(text.encode())
        out["stderr_kinds"] = dict(
            Counter(line.strip()[:60] for line in text.splitlines()).most_common(4)
        )
    with SimulatorProcess(stderr_pipe=True) as sim:  # stderr a pipe that nobody reads
        storm(sim.port, count)
        answered = ask(sim.port, 10)
        out["answered_with_undrained_stderr"] = answered is not None
        out["answer_seconds_with_undrained_stderr"] = None if answered is None else answered
    return out


# ---------------------------------------------------------------------- deaf


class NormalClient:
    """A process of its own (so this one's flood and GIL do not slow it) that asks the
    probe on one connection again and again, each answer's seconds on a line, until its
    stdin closes."""

    def __init__(self, port: int) -> None:
        self.process = subprocess.Popen(
            [sys.executable, __file__, "--normal-client", str(port)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        self.rtts: list[float] = []
        self.unanswered = 0
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            if line.strip() == "none":
                self.unanswered += 1
            elif line.strip():
                self.rtts.append(float(line))

    def stop(self) -> None:
        assert self.process.stdin is not None
        self.process.stdin.close()
        try:
            self.process.wait(70)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self._reader.join(5)


def normal_client(port: int) -> None:
    """The --normal-client mode: ask until stdin closes (or an answer takes over 60 s)."""
    stop = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
    with socket.create_connection((HOST, port), timeout=60) as sock:
        while not stop.is_set():
            rtt = ask(port, 60, sock)
            print("none" if rtt is None else f"{rtt:.6f}", flush=True)
            if rtt is None:
                return
            stop.wait(0.01)


def flood(
    clients: list[socket.socket], time_cap: float, request: bytes, sample: Callable[[], None]
) -> tuple[int, float]:
    """Send requests on every client until none can send (20 refusals 10 ms apart)."""
    chunk = request * 1000
    refusals = dict.fromkeys(clients, 0)
    sent = 0
    started = time.perf_counter()
    while refusals and time.perf_counter() - started < time_cap:
        progress = False
        for sock in list(refusals):
            try:
                sent += sock.send(chunk)
                refusals[sock] = 0
                progress = True
            except BlockingIOError:
                refusals[sock] += 1
                if refusals[sock] >= 20:
                    del refusals[sock]
            except OSError:
                del refusals[sock]
        sample()
        if not progress:
            time.sleep(0.01)
    return sent, time.perf_counter() - started


def watch_until_idle(sim: SimulatorProcess, cap: float) -> tuple[int, float]:
    """Sample RSS every 0.2 s until the simulator uses under 5% of a CPU for a second
    (or ``cap`` seconds pass); the highest RSS seen and how long it stayed busy."""
    started = time.monotonic()
    peak, window = sim.rss_kb(), [(started, sim.cpu_seconds())]
    while time.monotonic() - started < cap:
        time.sleep(0.2)
        peak = max(peak, sim.rss_kb())
        now = time.monotonic()
        window.append((now, sim.cpu_seconds()))
        window = [w for w in window if now - w[0] <= 1.05]
        elapsed = now - window[0][0]
        if elapsed >= 0.95 and (window[-1][1] - window[0][1]) / elapsed < 0.05:
            return peak, now - started - elapsed
    return peak, time.monotonic() - started


def deaf_section(count: int) -> dict[str, Any]:
    """Each deaf client asks for S10, set to 240 characters: 14 bytes in, 252 out."""
    out: dict[str, Any] = {}
    with SimulatorProcess() as sim:
        with socket.create_connection((HOST, sim.port), timeout=5) as setup:
            setup.sendall(b"PUT:RC8:10:S:8," + b"x" * 240 + b"\r")
            setup.recv(10)
        ask(sim.port, 5)
        before = sim.rss_kb()
        out["rss_before_mb"] = round(before / 1024, 1)
        normal = NormalClient(sim.port)
        clients = []
        for _ in range(count):
            sock = socket.create_connection((HOST, sim.port), timeout=5)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            sock.setblocking(False)
            clients.append(sock)
        peak = [before]

        def sample() -> None:
            peak[0] = max(peak[0], sim.rss_kb())

        sent, seconds = flood(clients, 120, b"GET:RC8:10:S:\r", sample)
        peak_kb, busy = watch_until_idle(sim, cap=120)
        peak_kb = max(peak_kb, peak[0])
        out["rss_after_mb"] = round(sim.rss_kb() / 1024, 1)
        out["rss_peak_sampled_mb"] = round(peak_kb / 1024, 1)
        out["rss_peak_vmhwm_mb"] = round(sim.rss_kb("VmHWM") / 1024, 1)
        out["rss_growth_per_client_kb"] = round((peak_kb - before) / max(count, 1), 1)
        out["simulator_busy_after_flood_s"] = round(busy, 1)
        out["requests_sent_mb"] = round(sent / 1e6, 1)
        out["flood_seconds"] = round(seconds, 1)
        normal.stop()
        rtts = normal.rtts
        out["normal_answers"] = len(rtts)
        out["normal_unanswered"] = normal.unanswered
        out["normal_rtt_median_ms"] = round(statistics.median(rtts) * 1000, 2) if rtts else None
        out["normal_rtt_max_ms"] = round(max(rtts) * 1000, 1) if rtts else None
        out["stderr_lines"] = len(sim.stderr().splitlines())
        for sock in clients:
            sock.close()
    return out


# ----------------------------------------------------------------------- fds


def fd_section(idle: int, limit: int) -> dict[str, Any]:
    if resource is None:
        return {"skipped": "no resource module (not POSIX)"}
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft < idle + 100:  # this process holds every idle connection
        resource.setrlimit(resource.RLIMIT_NOFILE, (min(hard, idle + 200), hard))

    def lower() -> None:
        resource.setrlimit(resource.RLIMIT_NOFILE, (limit, hard))

    out: dict[str, Any] = {"fd_limit": limit, "idle_connections": idle}
    with SimulatorProcess(preexec=lower) as sim:
        out["fds_at_start"] = sim.fds()
        clients: list[socket.socket] = []
        refused = 0
        for _ in range(idle):
            try:
                clients.append(socket.create_connection((HOST, sim.port), timeout=3))
            except OSError:
                refused += 1
        out["connect_failures"] = refused
        last = [-1]

        def settled() -> bool:
            now = sim.fds()
            same, last[0] = now == last[0], now
            return same

        wait_for(settled, 10)
        out["fds_with_idle"] = sim.fds()
        answered = ask(sim.port, 15)
        out["normal_answered"] = answered is not None
        out["normal_seconds"] = None if answered is None else round(answered, 3)
        second = ask(sim.port, 15)
        out["second_normal_seconds"] = None if second is None else round(second, 3)
        out["fds_after"] = sim.fds()
        out["alive_after"] = sim.process.poll() is None
        out |= idle_fates(clients)
        time.sleep(0.5)
        text = sim.stderr()
        out["stderr_lines"] = len(text.splitlines())
        out["stderr_tracebacks"] = text.count("Traceback")
        out["stderr_first_lines"] = text.splitlines()[:3]
        for sock in clients:
            sock.close()
    return out


def idle_fates(clients: list[socket.socket]) -> dict[str, int]:
    """How many idle connections the simulator closed, answered, or never took."""
    fates: Counter[str] = Counter()
    waiting = {}
    for sock in clients:
        sock.setblocking(False)
        try:
            data = sock.recv(100)
            fates["closed by the simulator"] += data == b""
            if data:
                fates["unexpected data"] += 1
            continue
        except BlockingIOError:
            pass
        except OSError:
            fates["closed by the simulator"] += 1
            continue
        try:
            sock.send(b"GET:RC8:1:I:\r")
            waiting[sock] = b""
        except OSError:
            fates["closed by the simulator"] += 1
    deadline = time.monotonic() + 5
    with selectors.DefaultSelector() as selector:  # not select(): fds over 1024
        for sock in waiting:
            selector.register(sock, selectors.EVENT_READ)
        while waiting and time.monotonic() < deadline:
            for key, _ in selector.select(0.2):
                sock = key.fileobj  # type: ignore[assignment]
                try:
                    data = sock.recv(100)
                except OSError:
                    data = b""
                if not data:
                    fates["closed by the simulator"] += 1
                elif data.endswith(b"\r"):
                    fates["answered"] += 1
                else:
                    continue
                selector.unregister(sock)
                del waiting[sock]
    fates["never answered (not accepted)"] += len(waiting)
    return {f"idle_{k.split(' (')[0].replace(' ', '_')}": v for k, v in fates.items()}


# ------------------------------------------------------------------- control


def control_section() -> dict[str, Any]:
    out: dict[str, Any] = {}
    with SimulatorProcess() as sim, socket.create_connection((HOST, sim.port), timeout=5) as sock:
        sock.sendall(b"SIM:SET:delay_ms=inf\r")
        out["set_delay_inf_reply"] = sock.recv(100).decode(errors="replace").strip()
        answered = ask(sim.port, 3, sock)
        out["get_answered_after"] = answered is not None
    try:
        refused = subprocess.run(
            [sys.executable, "-m", "rac_console", "sim", "--port", "0", "--delay", "inf"],
            capture_output=True,
            timeout=5,
            cwd=tempfile.gettempdir(),
        )
        out["option_delay_inf"] = f"refused (exit {refused.returncode})"
    except subprocess.TimeoutExpired:
        out["option_delay_inf"] = "accepted (it served)"
    return out


# ---------------------------------------------------------------------- main


def report(name: str, figures: dict[str, Any]) -> None:
    print(f"\n{name}")
    for key, value in figures.items():
        print(f"  {key:40} {value}")


def sections(chosen: list[str]) -> Iterator[str]:
    yield from (s for s in SECTIONS if s in chosen)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hostile", type=int, default=2000)
    parser.add_argument("--deaf", type=int, default=150)
    parser.add_argument("--idle", type=int, default=1100)
    parser.add_argument("--fd-limit", type=int, default=1024)
    parser.add_argument("--only", nargs="+", choices=SECTIONS, default=list(SECTIONS))
    parser.add_argument("--json", metavar="FILE")
    parser.add_argument("--normal-client", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.normal_client:
        normal_client(args.normal_client)
        return 0
    import rac_console  # only to say which copy is measured

    print(f"simulator package: {Path(rac_console.__file__).parent}")
    results: dict[str, Any] = {}
    for section in sections(args.only):
        if section == "noise":
            results[section] = noise_section(args.hostile)
        elif section == "deaf":
            results[section] = deaf_section(args.deaf)
        elif section == "fds":
            results[section] = fd_section(args.idle, args.fd_limit)
        else:
            results[section] = control_section()
        report(section, results[section])
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
