"""Five clients and an exporter on one agent, for an hour: one connection at the
controller, the agent's memory flat.

    python benchmarks/agent_soak.py [--seconds 3600] [--json FILE]

A controller of this script's own (asyncio, on 127.0.0.1: it answers a GET of I with
what a PUT wrote there, else a number that changes, any other line with ``0``, and
counts the connections it accepts) is held
by ``rac-console -H 127.0.0.1 -p PORT agent --watch ROWS --metrics 127.0.0.1:0`` (and
``--mqtt`` to a mosquitto of its own when one is installed): its exporter feeds 20
rows at 0.5 s whoever is attached. Attached to it, five clients of four kinds:

  - the console, in tmux at 120x40, watching ``I 0-49`` at 0.2 s, poll frames shown;
  - the REPL, in tmux, a ``put I 90 N`` typed every 10 s;
  - two ``rac-console watch I 0-29 --every 0.5 --json`` to /dev/null;
  - a script (``rac.connect``), a ``get`` and a ``put`` every second.

Every 10 s: the agent's memory (VmRSS), the connections the controller accepted, what
``agent status`` says (clients, missed frames) and the metrics page. It prints them at
1, 10, 30 and 60 minutes and at the end. Targets: one connection at the controller for
the whole hour; the agent's memory after the first minute flat (growth under 10%).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from dataclasses import asdict, dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SAMPLE_EVERY = 10.0
MARKS = (1, 10, 30, 60)  # minutes at which the figures are said on the way
ROWS = "\n".join(f'[[watch]]\ntype = "I"\nindex = {n}\n' for n in range(100, 120))
SCRIPT = """
import sys, time, rac_console as rac
n = 0
with rac.connect(sys.argv[1]) as rc:
    assert rc.via_agent, "the script did not attach"
    while True:
        n += 1
        rc.get("I", 5)
        rc.put("I", 91, n % 1000)
        time.sleep(1)
"""


class Controller:
    """A RAC controller of the benchmark's own that counts its connections."""

    def __init__(self) -> None:
        self.accepted = 0
        self.requests = 0
        self.memory: dict[bytes, bytes] = {}  # what PUTs wrote, read back by GETs
        self.port = 0
        ready = threading.Event()
        threading.Thread(target=self._run, args=(ready,), daemon=True).start()
        ready.wait(10)

    def _run(self, ready: threading.Event) -> None:
        async def serve() -> None:
            server = await asyncio.start_server(self._client, "127.0.0.1", 0)
            self.port = server.sockets[0].getsockname()[1]
            ready.set()
            await server.serve_forever()

        asyncio.run(serve())

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.accepted += 1
        try:
            while line := await reader.readuntil(b"\r"):
                self.requests += 1
                parts = line[:-1].split(b":")
                if parts[0] == b"PUT" and len(parts) == 5:  # PUT:RC8:N:I:3,V
                    self.memory[parts[2]] = parts[4].split(b",")[-1]
                    writer.write(b"0\r")
                elif parts[0] == b"GET" and parts[3:4] == [b"I"]:
                    value = self.memory.get(parts[2], b"%d" % (self.requests % 1000))
                    writer.write(b"0,3," + value + b"\r")
                else:
                    writer.write(b"0\r")
        except (asyncio.IncompleteReadError, ConnectionError):
            pass
        writer.close()


@dataclass
class Sample:
    minute: float
    agent_rss_mb: float
    accepted: int
    clients: int
    missed: int
    exporter_rows: int
    metrics_ok: bool


@dataclass
class Figures:
    seconds: float = 0.0
    samples: list[Sample] = field(default_factory=list)
    most_connections: int = 0
    fewest_clients: int = 99  # after the first minute (all five attached by then)
    rss_after_first_minute_mb: float = 0.0
    rss_end_mb: float = 0.0
    rss_most_mb: float = 0.0
    growth_after_first_minute: float = 0.0
    repl_puts: int = 0
    mqtt: bool = False


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=3600.0)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    if shutil.which("tmux") is None:
        print("agent_soak: needs tmux", file=sys.stderr)
        return 2
    home = Path(tempfile.mkdtemp(prefix="rac-agent-soak-"))
    env = {
        **os.environ,
        "HOME": str(home),
        "XDG_CONFIG_HOME": str(home / "config"),
        "XDG_STATE_HOME": str(home / "state"),
        "RAC_CONSOLE_AGENT_DIR": str(home / "agent"),
        "PYTHONPATH": str(ROOT),
    }
    env.pop("COLUMNS", None)
    env.pop("LINES", None)
    controller = Controller()
    where = ["-H", "127.0.0.1", "-p", str(controller.port)]
    rac = [sys.executable, "-m", "rac_console"]
    rows = home / "plant.toml"
    rows.write_text(ROWS, encoding="utf-8")
    feeds = ["--watch", str(rows), "--metrics", "127.0.0.1:0"]
    processes: list[subprocess.Popen[str]] = []
    figures = Figures()
    if shutil.which("mosquitto") is not None:
        broker = subprocess.Popen(
            ["mosquitto", "-p", "18830"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        processes.append(broker)
        feeds += ["--mqtt", "mqtt://127.0.0.1:18830/soak"]
        figures.mqtt = True
        time.sleep(0.5)
    agent = subprocess.Popen(
        [*rac, *where, "agent", *feeds], env=env, stdout=subprocess.PIPE, text=True
    )
    processes.append(agent)
    metrics = ""
    assert agent.stdout is not None
    for line in agent.stdout:
        if "/metrics" in line:
            metrics = line.split("http://")[1].split()[0].removesuffix("/metrics")
        if "listening on" in line:
            break
    threading.Thread(target=lambda: [None for _ in agent.stdout or ()], daemon=True).start()
    tmux = ["tmux", "-L", f"rac-agent-soak-{os.getpid()}"]
    line = " ".join([*rac, *where])
    quoted_env = " ".join(
        f"{k}={v}" for k, v in env.items() if k.startswith(("HOME", "XDG", "RAC", "PYTHONPATH"))
    )
    subprocess.run([*tmux, "new-session", "-d", "-s", "console", "-x", "120", "-y", "40",
                    f"env {quoted_env} {line}"], check=True)  # fmt: skip
    subprocess.run([*tmux, "new-session", "-d", "-s", "repl", "-x", "100", "-y", "30",
                    f"env {quoted_env} {line} repl"], check=True)  # fmt: skip
    time.sleep(4)
    subprocess.run([*tmux, "send-keys", "-t", "console", "watch I 0-49 every 0.2", "Enter"])
    watch = [*rac, *where, "watch", "I", "0-29", "--every", "0.5", "--json"]
    for _ in range(2):
        processes.append(
            subprocess.Popen(watch, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        )
    script = [sys.executable, "-c", SCRIPT, f"127.0.0.1:{controller.port}"]
    script_err = (home / "script.err").open("w")
    processes.append(subprocess.Popen(script, env=env, stderr=script_err, text=True))
    started = time.monotonic()
    marks = list(MARKS)
    next_put = started
    try:
        while (elapsed := time.monotonic() - started) < args.seconds:
            if time.monotonic() >= next_put:
                figures.repl_puts += 1
                subprocess.run(
                    [*tmux, "send-keys", "-t", "repl", f"put I 90 {figures.repl_puts}", "Enter"]
                )
                next_put += 10
            status = json.loads(
                subprocess.run([*rac, "agent", "status", "--json"], env=env,
                               capture_output=True, text=True).stdout or "{}"
            )  # fmt: skip
            try:
                with urllib.request.urlopen(f"http://{metrics}/metrics", timeout=5) as page:
                    metrics_ok = b'variable="I119"' in page.read()
            except OSError:
                metrics_ok = False
            sample = Sample(
                round(elapsed / 60, 2),
                round(rss_mb(agent.pid), 1),
                controller.accepted,
                len(status.get("clients", ())),
                sum(c.get("missed", 0) for c in status.get("clients", ())),
                sum(e.get("rows", 0) for e in status.get("exporters", ())),
                metrics_ok,
            )
            figures.samples.append(sample)
            figures.most_connections = max(figures.most_connections, controller.accepted)
            if sample.minute >= 1:
                figures.fewest_clients = min(figures.fewest_clients, sample.clients)
            if marks and elapsed >= marks[0] * 60:
                print(f"{marks.pop(0):>3} min: {sample}", flush=True)
                names = [c.get("name") for c in status.get("clients", ())]
                print(f"        clients: {', '.join(map(str, names))}", flush=True)
            time.sleep(SAMPLE_EVERY)
    finally:
        subprocess.run([*tmux, "kill-server"], capture_output=True)
        for process in processes:
            process.terminate()
        for process in processes:
            try:
                process.wait(20)
            except subprocess.TimeoutExpired:
                process.kill()
    figures.seconds = round(time.monotonic() - started, 1)
    after = [s.agent_rss_mb for s in figures.samples if s.minute >= 1] or [0.0]
    figures.rss_after_first_minute_mb, figures.rss_end_mb = after[0], after[-1]
    figures.rss_most_mb = max(after)
    figures.growth_after_first_minute = round(after[-1] / after[0] - 1, 3) if after[0] else 0.0
    last = figures.samples[-1] if figures.samples else None
    print(f"end: {last}")
    print(
        f"{figures.seconds:.0f} s; connections at the controller: at most "
        f"{figures.most_connections} (target 1); clients attached at least "
        f"{figures.fewest_clients} of 5; agent memory after 1 min "
        f"{figures.rss_after_first_minute_mb} MB, at the end {figures.rss_end_mb} MB, at most "
        f"{figures.rss_most_mb} MB, growth {figures.growth_after_first_minute:.1%} "
        f"(target under 10%); REPL puts typed {figures.repl_puts}; mqtt {figures.mqtt}"
    )
    if args.json:
        args.json.write_text(json.dumps(asdict(figures), indent=1), encoding="utf-8")
    kept = figures.most_connections == 1 and figures.fewest_clients == 5
    return 0 if kept and figures.growth_after_first_minute < 0.1 else 1


if __name__ == "__main__":
    sys.exit(main())
