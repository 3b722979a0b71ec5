"""The agent's polling against the in-process engine's: 200 rows at interval 0.

    python benchmarks/agent_polling.py [--seconds 8] [--rounds 3] [--clients 1]

Against the C responder, in turn each round (the order turned each round):

  - in process: an engine of this process (no front end but a drain), ``watch I 0-199``,
    ``interval 0``; its polls counted from the cycles it publishes;
  - through the agent: ``rac-console -H 127.0.0.1 -p PORT agent`` in a process of its own,
    and ``--clients`` clients of this process attached to it, each watching the same 200
    rows at interval 0; polls counted from the cycles the first client receives (what a
    client sees), and the requests the agent sent from ``agent status``.

Target: the agent's polling at least 0.9x the in-process engine's.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from bench_common import HERE, CPrograms, proc_cpu, start_responder

sys.path.insert(0, str(HERE.parent))

from rac_console.commands.target import Target
from rac_console.engine import Cycle, Engine, EngineOptions, Outbox
from rac_console.engine.setup.where import Where

TARGET_RATIO = 0.9


class Counter:
    """Drains an outbox as a front end would, counting the polls its cycles carry."""

    def __init__(self) -> None:
        self.woken = threading.Event()
        self.outbox = Outbox(notify=self.woken.set)
        self.polls = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._drain, daemon=True)
        self._thread.start()

    def _drain(self) -> None:
        while not self._stop.is_set():
            self.woken.wait(0.1)
            self.woken.clear()
            for event in self.outbox.drain().events:
                if isinstance(event, Cycle):
                    self.polls += len(event.samples)

    def stop(self) -> None:
        self._stop.set()


def rate(counter: Counter, seconds: float) -> float:
    time.sleep(1.0)  # at speed
    start, t0 = counter.polls, time.monotonic()
    time.sleep(seconds)
    return (counter.polls - start) / (time.monotonic() - t0)


def in_process(port: int, seconds: float) -> tuple[float, float]:
    counter = Counter()
    options = EngineOptions(timeout=5.0, interval=0.0, cycles=True, frames=False)
    engine = Engine(target=Target("127.0.0.1", port), options=options, outbox=counter.outbox)
    engine.start()
    engine.submit("watch I 0-199")
    engine.submit("interval 0")
    cpu0 = time.process_time()
    polls = rate(counter, seconds)
    cpu = (time.process_time() - cpu0) / (seconds + 1.0) * 100
    engine.stop()
    counter.stop()
    return polls, cpu


def through_agent(agent_pid: int, port: int, seconds: float, clients: int) -> tuple[float, float]:
    from rac_console.agent.client import attach

    counters = [Counter() for _ in range(clients)]
    engines = []
    options = EngineOptions(timeout=5.0, interval=0.0, cycles=True, frames=False)
    for counter in counters:
        engine = attach(
            Target("127.0.0.1", port), options, client="bench", where=Where.CONSOLE,
            outbox=counter.outbox,
        )  # fmt: skip
        if engine is None:
            raise RuntimeError("no agent to attach to")
        engine.start()
        engine.submit("watch I 0-199")
        engine.submit("interval 0")
        engines.append(engine)
    cpu0 = proc_cpu(agent_pid)
    polls = rate(counters[0], seconds)
    cpu = (proc_cpu(agent_pid) - cpu0) / (seconds + 1.0) * 100
    for engine in engines:
        engine.stop()
    for counter in counters:
        counter.stop()
    return polls, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--clients", type=int, default=1)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args()
    programs = CPrograms()
    server, what = start_responder(programs)
    alone: list[float] = []
    alone_cpu: list[float] = []
    agent_rates: list[float] = []
    agent_cpu: list[float] = []
    with tempfile.TemporaryDirectory(prefix="rac-agent-bench-") as tmp:
        os.environ["RAC_CONSOLE_AGENT_DIR"] = str(Path(tmp) / "agent")
        agent = subprocess.Popen(
            [sys.executable, "-m", "rac_console", "-H", "127.0.0.1", "-p", str(server.port),
             "agent"],
            cwd=HERE.parent, stdout=subprocess.PIPE, text=True,
        )  # fmt: skip
        try:
            assert agent.stdout is not None
            for line in agent.stdout:
                if "listening on" in line:
                    break
            print(f"against the {what} on 127.0.0.1:{server.port}", flush=True)
            for n in range(args.rounds):
                sides = ["alone", "agent"] if n % 2 == 0 else ["agent", "alone"]
                for side in sides:
                    if side == "alone":
                        polls, cpu = in_process(server.port, args.seconds)
                        alone.append(polls)
                        alone_cpu.append(cpu)
                    else:
                        polls, cpu = through_agent(agent.pid, server.port, args.seconds,
                                                   args.clients)  # fmt: skip
                        agent_rates.append(polls)
                        agent_cpu.append(cpu)
                print(f"round {n + 1}/{args.rounds} done", flush=True)
            status = subprocess.run(
                [sys.executable, "-m", "rac_console", "agent", "status", "--json"],
                cwd=HERE.parent, capture_output=True, text=True, check=False,
            ).stdout  # fmt: skip
        finally:
            agent.terminate()
            agent.wait(10)
            server.stop()
            programs.cleanup()
    base, via = statistics.median(alone), statistics.median(agent_rates)
    ratio = via / base
    print()
    print(f"{'side':<28} {'polls/s':>9} {'CPU %':>6}")
    print(f"{'in process (one engine)':<28} {base:>9,.0f} {statistics.median(alone_cpu):>6.0f}")
    label = f"through the agent ({args.clients} client{'s' if args.clients > 1 else ''})"
    print(f"{label:<28} {via:>9,.0f} {statistics.median(agent_cpu):>6.0f}  (the agent's CPU)")
    met = "yes" if ratio >= TARGET_RATIO else "NO"
    print(f"ratio {ratio:.2f} (target >= {TARGET_RATIO}: {met})")
    if status:
        targets = json.loads(status).get("targets", [])
        for target in targets:
            print(f"agent: {target['requests']:,} requests, {target['shared_polls']:,} polls "
                  "answered by another client's read")  # fmt: skip
    if args.json:
        Path(args.json).write_text(json.dumps({
            "in_process": alone, "agent": agent_rates, "ratio": ratio,
            "clients": args.clients,
        }))  # fmt: skip


if __name__ == "__main__":
    main()
