"""The simulator's TCP server against a C epoll server, both driven by the C load client.

    python benchmarks/sim_throughput.py [--seconds 2] [--rounds 5] [--sessions 50 1]
                                        [--pythonpath DIR] [--profile FILE]

``benchmarks/c/rac_client.c`` keeps one request (``GET:RC8:10:I:``) in flight on each of
SESSIONS connections, first against ``benchmarks/c/rac_epoll_responder.c``, then against
``python -m rac_console sim`` in its own process (``sim_harness.SimulatorProcess``), in
turn, ROUNDS times, so noise on this shared machine hits both sides alike. It prints the
medians, the median of the per-round ratios sim/C, and each server's CPU time per
request (from /proc/PID/stat: Linux). ``--pythonpath`` picks which copy of the package
the simulator runs (an older one, or one with uvloop beside it); ``--profile`` runs the
simulator under cProfile and prints where its time went.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import pstats
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from sim_harness import SimulatorProcess  # noqa: E402

PROGRAMS = ("rac_client", "rac_epoll_responder")


def compile_programs(folder: Path) -> dict[str, Path] | None:
    """The C programs built with ``cc -O2`` into ``folder``; None without a compiler."""
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        return None
    built = {}
    for name in PROGRAMS:
        binary = folder / name
        source = HERE / "c" / f"{name}.c"
        subprocess.run([compiler, "-O2", "-o", str(binary), str(source)], check=True)
        built[name] = binary
    return built


def cpu_seconds(pid: int) -> float:
    """User + system CPU of a running process (Linux /proc); nan elsewhere."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return float("nan")
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class Responder:
    """The C epoll responder as a child process; it prints its port."""

    def __init__(self, binary: Path) -> None:
        self.process = subprocess.Popen([str(binary), "0"], stdout=subprocess.PIPE, text=True)
        assert self.process.stdout is not None
        self.port = int(self.process.stdout.readline())
        self.pid = self.process.pid

    def stop(self) -> None:
        self.process.kill()
        self.process.wait(10)
        if self.process.stdout is not None:
            self.process.stdout.close()


def drive(client: Path, port: int, pid: int, sessions: int, seconds: float) -> tuple[float, float]:
    """Requests/s the C client got, and the server's CPU µs per request meanwhile."""
    before = cpu_seconds(pid)
    out = subprocess.run(
        [str(client), str(port), str(sessions), str(seconds)],
        capture_output=True, text=True, check=True, timeout=seconds + 60,
    ).stdout  # fmt: skip
    rate = float(out)
    used = cpu_seconds(pid) - before
    return rate, used / max(rate * seconds, 1.0) * 1e6


def measure(
    client: Path, servers: dict[str, tuple[int, int]], sessions: int, seconds: float, rounds: int
) -> dict[str, list[tuple[float, float]]]:
    """Each server once per round, in turn, after a short warm-up of each."""
    for port, pid in servers.values():
        drive(client, port, pid, sessions, min(0.5, seconds))
    results: dict[str, list[tuple[float, float]]] = {name: [] for name in servers}
    for _ in range(rounds):
        for name, (port, pid) in servers.items():
            results[name].append(drive(client, port, pid, sessions, seconds))
    return results


def report(sessions: int, results: dict[str, list[tuple[float, float]]]) -> list[str]:
    c, sim = results["C epoll"], results["sim"]
    rows = []
    for name, runs in results.items():
        rates = [rate for rate, _ in runs]
        cpu = statistics.median(us for _, us in runs)
        rows.append(
            f"| {sessions:>8} | {name:<8} | {statistics.median(rates):>10,.0f} "
            f"| {min(rates):>9,.0f}–{max(rates):<9,.0f} | {cpu:>8.2f} |"
        )
    ratio = statistics.median(s / c for (s, _), (c, _) in zip(sim, c, strict=True))
    cpu_ratio = statistics.median(s / c for (_, s), (_, c) in zip(sim, c, strict=True))
    rows.append(f"| {sessions:>8} | sim / C  | {ratio:>9.2f}x | {'':>19} | {cpu_ratio:>7.1f}x |")
    return rows


def print_profile(path: Path, top: int = 25) -> None:
    stats = pstats.Stats(str(path))
    print(f"\nsimulator profile (cProfile, {stats.total_tt:.1f} s, top {top} by own time):")  # type: ignore[attr-defined]
    stats.sort_stats("tottime").print_stats(top)


def simulator_loop(pythonpath: str | None) -> str:
    """Which event loop ``rac-console sim`` will run on with this PYTHONPATH."""
    env = dict(os.environ)
    if pythonpath:
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [pythonpath, env.get("PYTHONPATH")]))
    probe = "import importlib.util as u; print('uvloop' if u.find_spec('uvloop') else 'asyncio')"
    found = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=False
    ).stdout.strip()
    if found == "uvloop" and os.environ.get("RAC_CONSOLE_NO_UVLOOP"):
        return "asyncio (uvloop turned off)"
    return found or "unknown"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=2.0, help="per measurement")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--sessions", type=int, nargs="+", default=[50, 1])
    parser.add_argument("--pythonpath", help="run the simulator with this PYTHONPATH first")
    parser.add_argument("--profile", type=Path, help="run the simulator under cProfile")
    parser.add_argument("--json", type=Path, help="write each session count's sim/C ratio")
    args = parser.parse_args()
    print("$ " + shlex.join([Path(sys.executable).name, *sys.argv]))
    print(
        f"# {platform.python_implementation()} {platform.python_version()}, "
        f"{os.cpu_count()} CPUs, load {' '.join(f'{x:.2f}' for x in os.getloadavg())}, "
        f"simulator on {simulator_loop(args.pythonpath)}, {args.rounds} rounds of "
        f"{args.seconds:g} s, C client: one request in flight per session"
    )
    if not sys.platform.startswith("linux"):
        print("skipped: the C epoll responder and /proc CPU accounting need Linux")
        return 0
    with tempfile.TemporaryDirectory() as folder:
        try:
            built = compile_programs(Path(folder))
        except subprocess.CalledProcessError as exc:
            print(f"skipped: the C programs did not compile ({exc})")
            return 0
        if built is None:
            print("skipped: no C compiler (cc or gcc) on PATH")
            return 0
        return run(args, built)


def run(args: argparse.Namespace, built: dict[str, Path]) -> int:
    stops: list[Callable[[], None]] = []
    try:
        responder = Responder(built["rac_epoll_responder"])
        stops.append(responder.stop)
        sim = SimulatorProcess(pythonpath=args.pythonpath, profile=args.profile)
        stops.append(sim.stop)
        servers = {"C epoll": (responder.port, responder.pid), "sim": (sim.port, sim.pid)}
        lines = [
            "| sessions | server   |  req/s med | min–max             | CPU µs/req |",
            "|---------:|----------|-----------:|---------------------|-----------:|",
        ]
        started = time.monotonic()
        figures: dict[str, float] = {}
        for sessions in args.sessions:
            results = measure(built["rac_client"], servers, sessions, args.seconds, args.rounds)
            lines += report(sessions, results)
            sim_c = zip(results["sim"], results["C epoll"], strict=True)
            figures[f"sim_to_c_{sessions}"] = statistics.median(s / c for (s, _), (c, _) in sim_c)
        if args.json is not None:
            args.json.write_text(json.dumps(figures) + "\n", encoding="utf-8")
        print("\n".join(lines))
        print(f"# {time.monotonic() - started:.0f} s; CPU µs/req: the server's user+system time")
        if sim.stderr().strip():
            print("simulator stderr:\n" + sim.stderr().strip())
    finally:
        for stop in reversed(stops):
            stop()
    if args.profile:
        print_profile(args.profile)
    return 0


if __name__ == "__main__":
    sys.exit(main())
