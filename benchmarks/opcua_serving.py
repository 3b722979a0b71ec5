"""What serving OPC UA costs polling: 1,000 variables, subscribed clients, greedy ones.

    python benchmarks/opcua_serving.py [--seconds 10] [--quick]

Every side runs the real CLI, ``rac-console agent --watch FILE --log-csv FILE`` with a
watch list of I 0-999 (each row's ``every`` the interval), against
the C responder (``benchmarks/c/rac_responder.c``, ``cc -O2``) answering a counter that
grows at every GET: every variable changes at every poll, the worst case for the
server (each poll a data change to serve). The figures are read from outside: the
gaps between the CSV log's rows (one per poll cycle), the agent's CPU time (``/proc``), what
the clients counted.

- ``0.2 s``: ``every = 0.2``: the cycles a second, the gap between cycles (mean, p95,
  longest) against the 0.2 s asked, and the watch's CPU;
  - without ``--opcua``, with it and no client, with 20 clients each subscribed to 100 of
    the variables (a screen's worth, each client its own 100, overlapping; publishing
    every 200 ms: the notifications a second they got, of 10,000 a second changed), and
    with 4 greedy clients browsing, reading all 1,000, subscribing and dropping the
    subscription, flat out (their rounds a second);
- ``flat out``: ``every = 0``: polls a second without the server, with a busy loop
  beside (nice 19: on this two-core machine a busy neighbour makes the ping-pong with
  the responder faster, the cores never idle), with the server, with it and 20
  subscribed clients; the ratio to the first.

The clients are processes of their own at ``nice 19``: in a plant they run on other
machines; here they share the two cores, and must not take the watch's turn for what
the server costs it.
"""

from __future__ import annotations

import argparse
import itertools
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from bench_common import CPrograms, Server, warn  # noqa: E402

VARIABLES = 1000
CLIENT = """
import asyncio, sys, time
from asyncua import Client
url, mode = sys.argv[1], sys.argv[2]
count = 0
class Handler:
    def datachange_notification(self, node, value, data):
        global count
        count += 1
class Quiet:
    def datachange_notification(self, node, value, data):
        pass
async def main():
    global count
    async with Client(url, timeout=30) as client:
        ns = await client.get_namespace_index("urn:rac-console:watched")
        root = await client.nodes.objects.get_child([f"{ns}:RacConsole"])
        while True:
            folders = await root.get_children()
            nodes = await folders[0].get_children() if folders else []
            if len(nodes) >= int(sys.argv[3]):
                break
            await asyncio.sleep(0.2)
        if mode == "subscribe":  # a screen's worth: 100 of them, each client its own
            first = int(sys.argv[4]) * 50 % len(nodes)
            sub = await client.create_subscription(200, Handler())
            await sub.subscribe_data_change((nodes + nodes)[first : first + 100])
        print("ready", flush=True)
        start = time.monotonic()
        while True:
            if mode == "greedy":
                await folders[0].get_children()
                await client.read_values(nodes)
                sub = await client.create_subscription(100, Quiet())
                await sub.subscribe_data_change(nodes)
                await sub.delete()
                count += 1
            else:
                await asyncio.sleep(0.5)
            print(f"{count} {time.monotonic() - start:.3f}", flush=True)
asyncio.run(main())
"""


@dataclass
class Figures:
    cycles_per_s: float
    mean_gap_ms: float
    p95_gap_ms: float
    longest_gap_ms: float
    cpu_percent: float
    clients: str = ""


class Watch:
    """The agent with a watch list of the 1,000 rows (``every`` the interval) and its
    ``--log-csv``: the time of each cycle's row, its words."""

    def __init__(self, home: Path, responder: int, every: str, opcua: bool) -> None:
        (home / "rac.toml").write_text("")
        (home / "run").mkdir(mode=0o700)
        rows = "".join(
            f'[[watch]]\ntype = "I"\nindex = {n}\nevery = {every}\n\n' for n in range(VARIABLES)
        )
        (home / "watch.toml").write_text(rows)
        self.csv = home / "cycles.csv"
        env = dict(os.environ, HOME=str(home), XDG_CONFIG_HOME=str(home / "config"),
                   XDG_STATE_HOME=str(home / "state"), XDG_DATA_HOME=str(home / "data"),
                   XDG_RUNTIME_DIR=str(home / "run"), RAC_CONSOLE_CONFIG=str(home / "rac.toml"),
                   PYTHONPATH=str(ROOT))  # fmt: skip
        args = [
            "-H",
            "127.0.0.1",
            "-p",
            str(responder),
            "agent",
            "--watch",
            str(home / "watch.toml"),
        ]
        args += ["--log-csv", str(self.csv)]
        if opcua:
            args += ["--opcua", "opc.tcp://127.0.0.1:0"]
        self.process = subprocess.Popen(
            [sys.executable, "-m", "rac_console", *args],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        self.times: list[float] = []
        self.url: str | None = None
        self.err: list[str] = []
        self._lock = threading.Lock()
        self._stopping = False
        threading.Thread(target=self._rows, daemon=True).start()
        threading.Thread(target=self._errors, daemon=True).start()

    def _rows(self) -> None:
        """The CSV's rows as they are written (the file looked at every 20 ms)."""
        while not self.csv.exists() and not self._stopping:
            time.sleep(0.02)
        with self.csv.open() as rows:
            pending = ""
            while not self._stopping:
                chunk = rows.read()
                if not chunk:
                    time.sleep(0.02)
                    continue
                *lines, pending = (pending + chunk).split("\n")
                for line in lines:
                    if line[:1].isdigit():
                        at = datetime.fromisoformat(line.split(",", 1)[0]).timestamp()
                        with self._lock:
                            self.times.append(at)

    def _errors(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.err.append(line.rstrip("\n"))
            if match := re.search(r"over OPC UA at (opc\.tcp://\S+)", line):
                self.url = match.group(1)

    def wait_first(self, opcua: bool, deadline: float = 60) -> None:
        end = time.monotonic() + deadline
        while len(self.times) < 3 or (opcua and self.url is None):
            if time.monotonic() > end or self.process.poll() is not None:
                raise SystemExit(f"the agent did not start: {self.err}")
            time.sleep(0.05)

    def cpu_seconds(self) -> float:
        fields = Path(f"/proc/{self.process.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def window(self, seconds: float) -> Figures:
        cpu_before, wall_before = self.cpu_seconds(), time.monotonic()
        with self._lock:
            start = len(self.times)
        time.sleep(seconds)
        with self._lock:
            seen = self.times[max(0, start - 1) :]
        cpu = (self.cpu_seconds() - cpu_before) / (time.monotonic() - wall_before) * 100
        gaps = [(b - a) * 1000 for a, b in itertools.pairwise(seen)] or [float("nan")]
        span = seen[-1] - seen[0] if len(seen) > 1 else 0.0
        p95 = sorted(gaps)[max(0, int(len(gaps) * 0.95) - 1)]
        return Figures(
            (len(seen) - 1) / span if span else 0.0,
            statistics.fmean(gaps),
            p95,
            max(gaps),
            cpu,
        )

    def stop(self) -> None:
        self._stopping = True
        self.process.terminate()
        try:
            self.process.wait(20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(20)


class Clients:
    """``n`` client processes (nice 19), each subscribed or greedy."""

    def __init__(self, url: str, mode: str, n: int) -> None:
        self.processes = [
            subprocess.Popen(
                [
                    "nice",
                    "-n",
                    "19",
                    sys.executable,
                    "-c",
                    CLIENT,
                    url,
                    mode,
                    str(VARIABLES),
                    str(n_),
                ],
                stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL,
                text=True,
            )
            for n_ in range(n)
        ]
        self.last: list[tuple[int, float]] = [(0, 0.0)] * n
        self.ready = [threading.Event() for _ in range(n)]
        for n_, process in enumerate(self.processes):
            threading.Thread(target=self._read, args=(n_, process), daemon=True).start()

    def _read(self, n: int, process: subprocess.Popen[str]) -> None:
        assert process.stdout is not None
        for line in process.stdout:
            if line.startswith("ready"):
                self.ready[n].set()
            else:
                count, elapsed = line.split()
                self.last[n] = (int(count), float(elapsed))

    def wait_ready(self, deadline: float = 900) -> None:
        end = time.monotonic() + deadline
        for event in self.ready:
            if not event.wait(max(0.0, end - time.monotonic())):
                raise SystemExit("a client did not get ready")

    def rate(self) -> float:
        """Counted a second, all clients together (from their own clocks)."""
        return sum(count / elapsed for count, elapsed in self.last if elapsed)

    def stop(self) -> None:
        for process in self.processes:
            process.kill()
        for process in self.processes:
            process.wait(10)


def side(responder: int, interval: str, seconds: float, opcua: bool, clients: tuple[str, int]
         | None = None) -> Figures:  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="rac-opcua-") as folder:
        watch = Watch(Path(folder), responder, interval, opcua)
        running: Clients | None = None
        burner: subprocess.Popen[bytes] | None = None
        try:
            watch.wait_first(opcua)
            if clients is not None and clients[0] == "burn":  # a busy loop, nice 19
                burner = subprocess.Popen(["nice", "-n", "19", "sh", "-c", "while :; do :; done"])
            elif clients is not None and watch.url is not None:
                running = Clients(watch.url, *clients)
                running.wait_ready()
            figures = watch.window(seconds)
            if running is not None:
                unit = "notifications/s" if clients and clients[0] == "subscribe" else "rounds/s"
                figures.clients = f"{running.rate():,.0f} {unit}"
            return figures
        finally:
            if running is not None:
                running.stop()
            if burner is not None:
                burner.kill()
                burner.wait()
            watch.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--quick", action="store_true", help="3 s windows, 5 clients")
    options = parser.parse_args()
    seconds = 3.0 if options.quick else options.seconds
    many = 5 if options.quick else 20
    programs = CPrograms()
    if programs.responder is None:
        warn(f"{programs.error}: this benchmark needs the C responder")
        raise SystemExit(1)
    responder = Server([str(programs.responder), "0", "changing"])
    try:
        print(f"{VARIABLES} variables (I 0-{VARIABLES - 1}), each changing at every poll; "
              f"C responder; windows of {seconds:g} s; {os.cpu_count()} cores")  # fmt: skip
        print(f"\n{'at 0.2 s':34} {'cycles/s':>8} {'mean gap':>9} {'p95 gap':>8} "
              f"{'longest':>8} {'CPU':>5}  clients")  # fmt: skip
        rows = [
            ("no server", False, None),
            ("--opcua, no client", True, None),
            (f"--opcua, {many} subscribed", True, ("subscribe", many)),
            ("--opcua, 4 greedy", True, ("greedy", 4)),
        ]
        for name, opcua, clients in rows:
            f = side(responder.port, "0.2", seconds, opcua, clients)
            gaps = f"{f.mean_gap_ms:7.1f}ms {f.p95_gap_ms:6.1f}ms {f.longest_gap_ms:6.1f}ms"
            print(f"{name:34} {f.cycles_per_s:8.2f} {gaps} {f.cpu_percent:4.0f}%  {f.clients}",
                  flush=True)  # fmt: skip
        print(f"\n{'flat out (every = 0)':34} {'polls/s':>8} {'ratio':>6} {'CPU':>5}  clients")
        base = None
        for name, opcua, clients in [
            ("no server", False, None),
            ("no server, a busy loop beside", False, ("burn", 1)),
            ("--opcua, no client", True, None),
            (f"--opcua, {many} subscribed", True, ("subscribe", many)),
        ]:
            f = side(responder.port, "0", seconds, opcua, clients)
            polls = f.cycles_per_s * VARIABLES
            base = base or polls
            print(f"{name:34} {polls:8,.0f} {polls / base:6.2f} {f.cpu_percent:4.0f}%  {f.clients}",
                  flush=True)  # fmt: skip
    finally:
        responder.stop()


if __name__ == "__main__":
    main()
