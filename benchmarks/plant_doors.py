"""The plant's doors: what a hostile broker, idle connections and scrapers cost polling.

    python benchmarks/plant_doors.py [--old DIR] [--seconds 10] [--quick]

Every side runs the real CLI, ``python -m rac_console --json watch I 1``, against the
C responder (``benchmarks/c/rac_responder.c``, ``cc -O2``), with ``PYTHONPATH`` set to
the checkout measured: this one, and with ``--old DIR`` another (a ``git worktree`` of
an earlier commit), side by side in one run. The figures are read from outside: the
gaps between the watch's own lines (each poll prints one), its peak resident memory
and its threads (``/proc``), what the broker saw.

- ``quiet``: ``--every 0.05``, no plant: the longest gap between two polls, the peak RSS;
- the four brokers of ``tests/support/brokers.py`` (a 256 MB CONNACK, junk, a PUBACK
  storm, silence), each with ``--mqtt`` to it: the longest gap, the peak RSS, the
  connections the broker saw (a broker dropped and tried again with backoff: a few);
- ``idle 1000``: ``--metrics 0`` and 1,000 connections to it that send nothing: threads,
  peak RSS, the longest gap;
- ``scrape 0`` and ``scrape 4``: ``--every 0`` (flat out) with ``--metrics 0``, nobody
  scraping, then four processes scraping as fast as they are answered: polls a second,
  their ratio, and the scrapes answered a second.

This checkout's watch reads ``[mqtt] keepalive = 2`` (the silent broker is found out in
4 s); an older one, which has no such key, its own 15 s.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import resource
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT))  # the tests' brokers: tests.support.brokers

from bench_common import CPrograms, start_responder  # noqa: E402
from tests.support.brokers import HOSTILE, hostile_broker  # noqa: E402

SCRAPER = """
import sys, time, urllib.request
url, until = sys.argv[1], time.monotonic() + float(sys.argv[2])
done = 0
while time.monotonic() < until:
    try:
        with urllib.request.urlopen(url, timeout=5) as page:
            page.read()
        done += 1
    except OSError:
        pass
print(done)
"""


@dataclass
class Figures:
    polls_per_s: float
    longest_gap_ms: float
    peak_rss_mb: float
    threads: int
    lines: int
    said: list[str]
    extra: str = ""


class Watch:
    """The CLI's watch, its JSON lines and stderr kept as they come."""

    def __init__(self, checkout: Path, home: Path, *args: str) -> None:
        env = dict(os.environ)
        env.update(
            PYTHONPATH=str(checkout),
            HOME=str(home),
            XDG_CONFIG_HOME=str(home / "config"),
            XDG_STATE_HOME=str(home / "state"),
            RAC_CONSOLE_CONFIG=str(home / "rac.toml"),
            PYTHONIOENCODING="utf-8",
        )
        self.process = subprocess.Popen(
            [sys.executable, "-m", "rac_console", "--json", "watch", *args],
            env=env,
            cwd=str(home),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.times: list[tuple[float, int]] = []  # (line time, cycle)
        self.err: list[str] = []
        self._lock = threading.Lock()
        threading.Thread(target=self._out, daemon=True).start()
        threading.Thread(target=self._errors, daemon=True).start()
        self.metrics_url: str | None = None

    def _out(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            if line.startswith("{"):
                data = json.loads(line)
                at = datetime.fromisoformat(data["time"]).timestamp()
                with self._lock:
                    self.times.append((at, data["cycle"]))

    def _errors(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.err.append(line.rstrip("\n"))
            if "serving the watched values at " in line:
                self.metrics_url = line.rsplit(" ", 1)[1].strip()

    def wait_first(self, deadline: float = 30) -> None:
        end = time.monotonic() + deadline
        while not self.times or (self.metrics_url is None and "--metrics" in self.process.args):
            if time.monotonic() > end or self.process.poll() is not None:
                raise SystemExit(f"the watch did not start: {self.err}")
            time.sleep(0.05)

    def proc(self, field: str) -> int:
        for line in Path(f"/proc/{self.process.pid}/status").read_text().splitlines():
            if line.startswith(f"{field}:"):
                return int(line.split()[1])
        return 0

    def window(self, seconds: float) -> Figures:
        with self._lock:
            start = len(self.times)
        time.sleep(seconds)
        with self._lock:
            seen = self.times[max(0, start - 1) :]
        peak, threads = self.proc("VmHWM") / 1024, self.proc("Threads")
        gaps = [b[0] - a[0] for a, b in itertools.pairwise(seen)]
        span = seen[-1][0] - seen[0][0] if len(seen) > 1 else 0.0
        cycles = seen[-1][1] - seen[0][1] if len(seen) > 1 else 0
        return Figures(
            cycles / span if span else 0.0,
            max(gaps, default=float("nan")) * 1000,
            peak,
            threads,
            len(seen),
            [e for e in self.err if "MQTT" in e or "metrics" in e],
        )

    def stop(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(20)


@contextmanager
def watch(checkout: Path, *args: str) -> Iterator[Watch]:
    with tempfile.TemporaryDirectory(prefix="rac-doors-") as folder:
        home = Path(folder)
        new = (checkout / "rac_console" / "plant" / "mqtt_guard.py").exists()
        (home / "rac.toml").write_text("[mqtt]\nkeepalive = 2\n" if new else "")
        running = Watch(checkout, home, *args)
        try:
            running.wait_first()
            yield running
        finally:
            running.stop()


def side_quiet(checkout: Path, target: list[str], seconds: float) -> Figures:
    with watch(checkout, "I", "1", "--every", "0.05", *target) as running:
        return running.window(seconds)


def side_hostile(name: str) -> Callable[[Path, list[str], float], Figures]:
    def side(checkout: Path, target: list[str], seconds: float) -> Figures:
        broker = hostile_broker(name)
        try:
            url = f"mqtt://127.0.0.1:{broker.port}/bench"
            with watch(checkout, "I", "1", "--every", "0.05", "--mqtt", url, *target) as running:
                figures = running.window(seconds)
            figures.extra = f"{broker.count()[0]} connections"
            return figures
        finally:
            broker.close()

    return side


def side_idle(checkout: Path, target: list[str], seconds: float) -> Figures:
    with watch(checkout, "I", "1", "--every", "0.05", "--metrics", "0", *target) as running:
        assert running.metrics_url is not None
        port = int(running.metrics_url.rsplit(":", 1)[1].split("/")[0])
        before = running.proc("Threads")
        held = []
        for _ in range(1000):
            sock = socket.socket()
            sock.setblocking(False)
            sock.connect_ex(("127.0.0.1", port))
            held.append(sock)
        try:
            figures = running.window(seconds)
        finally:
            for sock in held:
                sock.close()
        figures.extra = f"threads {before} before"
        return figures


def side_scrape(scrapers: int) -> Callable[[Path, list[str], float], Figures]:
    def side(checkout: Path, target: list[str], seconds: float) -> Figures:
        with watch(checkout, "I", "1", "--every", "0", "--metrics", "0", *target) as running:
            assert running.metrics_url is not None
            children = [
                subprocess.Popen(
                    [sys.executable, "-c", SCRAPER, running.metrics_url, str(seconds)],
                    stdout=subprocess.PIPE,
                    text=True,
                )
                for _ in range(scrapers)
            ]
            figures = running.window(seconds)
            answered = sum(int(child.communicate(timeout=60)[0] or 0) for child in children)
        figures.extra = f"{answered / seconds:.0f} scrapes/s answered" if scrapers else ""
        return figures

    return side


SIDES: dict[str, Callable[[Path, list[str], float], Figures]] = {
    "quiet": side_quiet,
    **{name: side_hostile(name) for name in HOSTILE},
    "idle 1000": side_idle,
    "scrape 0": side_scrape(0),
    "scrape 4": side_scrape(4),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--old", type=Path, help="another checkout, measured beside this one")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--quick", action="store_true", help="2 s a side: a check it runs")
    args = parser.parse_args()
    seconds = 2.0 if args.quick else args.seconds
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(soft, min(hard, 4096)), hard))
    checkouts = {"this": ROOT} | ({"old": args.old.resolve()} if args.old else {})
    programs = CPrograms()
    responder, kind = start_responder(programs)
    target = ["-H", "127.0.0.1", "-p", str(responder.port)]
    print(f"plant doors: watch I 1 against the {kind}, {seconds:g} s a side", flush=True)
    head = f"{'side':<32} {'checkout':<6} {'polls/s':>8} {'longest gap':>12} {'peak RSS':>9}"
    print(f"{head} {'threads':>7}  notes")
    rates: dict[tuple[str, str], float] = {}
    try:
        for side, measure in SIDES.items():
            for label, checkout in checkouts.items():
                figures = measure(checkout, target, seconds)
                rates[side, label] = figures.polls_per_s
                said = "; ".join(s.removeprefix("rac-console: ")[:70] for s in figures.said[:2])
                print(
                    f"{side:<32} {label:<6} {figures.polls_per_s:>8.0f} "
                    f"{figures.longest_gap_ms:>9.0f} ms {figures.peak_rss_mb:>6.0f} MB "
                    f"{figures.threads:>7}  {figures.extra}{' | ' if figures.extra else ''}{said}",
                    flush=True,
                )
        for label in checkouts:
            quiet, busy = rates.get(("scrape 0", label)), rates.get(("scrape 4", label))
            if quiet and busy:
                print(f"four scrapers flat out, {label}: polling at {busy / quiet:.2f}x")
    finally:
        responder.stop()
        programs.cleanup()


if __name__ == "__main__":
    main()
