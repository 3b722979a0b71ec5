"""Feeding the plant: the engine's polling rate with publishing off, to MQTT, to /metrics.

    python benchmarks/plant_publish.py [--rows 100] [--seconds 3] [--rounds 6] [--old DIR]
                                       [--placement pinned|free] [--callgrind] [--quick]

An engine watches I 0-(ROWS-1) at interval 0 (flat out, no frames shown, as a CLI
watch) against the C responder (``benchmarks/c/rac_responder.c``, ``cc -O2``), in a
process of its own for each measurement. Sides, each once per round, in turn (the order
turned each round), so noise on a shared machine hits every side alike:

- ``off``: no plant at all;
- ``mqtt``: ``EngineOptions(publish=mqtt://127.0.0.1:PORT/bench)``, to a mosquitto this
  script starts on 127.0.0.1 and a free port (and stops at the end);
- ``metrics``: ``EngineOptions(metrics=MetricsBoard())``: what the engine's thread does
  for ``--metrics`` (the board written at each flush); no HTTP server, nobody scrapes.

each against two responders:

- ``fixed``: the same reply every time: no row changes, publishing costs only the
  comparison the engine makes anyway (nothing is handed to the feed);
- ``changing``: the responder started with ``changing``, a GET of I answers a counter
  that grows at every request: every poll changes its row, the worst case. Rows are
  handed to the feed at each flush (every 10 ms while polling), the feed keeps the latest
  payload of each topic, and at most 200 messages are in flight: the published rate is
  bounded by what the broker acknowledges, not by the polling rate.

With ``--old DIR`` (a checkout of another version of the package, read only), its
``mqtt`` and ``metrics`` run too, in the same rounds (``mqtt-old``, ``metrics-old``),
their ratios to this checkout's ``off``.

A rate is polls counted from the engine's poll cycles (``Cycle.monotonic``) over the
measured window, after a warm-up (and, with MQTT, once the feed is connected); the CPU
per poll is the whole process's (every thread: the engine's, the feed's, paho's) over
that window. ``msgs/s`` is ``MqttFeed.sent`` over the window: messages the broker
acknowledged (QoS 1, PUBACK). The goal: ``mqtt`` and ``metrics`` >= 0.9x ``off``, the
median of the per-round ratios, for each responder.

Placement (``pinned``, the default on two CPUs or more): the engine's process and the
responder on one CPU (as ``run.py`` measures the engine: a request costs the client's
CPU, the responder's and two switches, not a hypervisor's cross-CPU wake-up), mosquitto
on another (a broker is another machine at a plant). ``free``: wherever the scheduler
puts them.

``--callgrind``: each side also runs a fixed number of poll cycles under ``valgrind
--tool=callgrind`` (twice, N and 2N cycles: the start-up cancels out): instructions per
poll, which do not swing with the machine's load. Under callgrind the engine runs some
fifty times slower and the broker does not, so nearly every change goes out: ``changing
mqtt`` counts there about a message a poll, far more than in real time (an upper bound).
``--quick``: one short round, a check that it runs, not a measurement.
"""

from __future__ import annotations

import argparse
import getpass
import json
import os
import re
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
sys.path.insert(0, str(HERE.parent))

from bench_common import CPrograms, Run, Server, alternate, report_run  # noqa: E402

HOST = "127.0.0.1"
PREFIX = "bench"
GOAL = 0.9
MODES = ("off", "mqtt", "metrics")
VALUES = ("fixed", "changing")


# ------------------------------------------------------------------ the measuring child


def measure(mode: str, port: int, broker: int, rows: int, seconds: float, warm: float) -> None:
    """One engine, ``rows`` rows flat out for ``seconds`` after ``warm``; its JSON line."""
    from rac_console.commands.plant import parse_mqtt_address
    from rac_console.engine import Cycle, Engine, EngineOptions
    from rac_console.plant.metrics import MetricsBoard

    options = EngineOptions(
        interval=0.0,
        cycles=True,
        frames=False,
        publish=parse_mqtt_address(f"mqtt://{HOST}:{broker}/{PREFIX}") if mode == "mqtt" else None,
        metrics=MetricsBoard() if mode == "metrics" else None,
        plant_name="rc8",
    )
    engine = Engine(HOST, port, options=options)
    engine.start()
    engine.submit(f"watch I 0-{rows - 1}")
    tap = engine._publisher.tap  # a benchmark reads the counter
    feed = tap.mqtt if tap is not None else None
    deadline = time.monotonic() + 30
    while feed is not None and not feed.connected:
        if time.monotonic() > deadline:
            raise SystemExit(f"the MQTT feed did not connect to {HOST}:{broker}")
        time.sleep(0.01)
    thread = engine._thread.native_id  # the engine's thread alone: /proc/self/task/TID

    def engine_cpu() -> float:
        return thread_cpu(thread)

    warm_until = time.monotonic() + warm
    start: tuple[float, float, int, float] | None = None  # Cycle.monotonic, CPU, sent, engine
    polls = 0
    try:
        while True:
            time.sleep(0.005)
            for event in engine.outbox.drain().events:
                if not isinstance(event, Cycle):
                    continue
                stamp = event.monotonic
                if start is None:
                    if stamp >= warm_until:
                        sent = feed.sent if feed else 0
                        start = (stamp, time.process_time(), sent, engine_cpu())
                    continue
                polls += len(event.samples)
                if stamp - start[0] >= seconds:
                    sent = (feed.sent if feed else 0) - start[2]
                    cpu = time.process_time() - start[1]
                    report_run(
                        polls, stamp - start[0], cpu, sent=sent, engine=engine_cpu() - start[3]
                    )
                    return
    finally:
        engine.stop()


def thread_cpu(tid: int | None) -> float:
    """User + system CPU seconds of one of this process's threads (Linux); nan elsewhere."""
    try:
        fields = Path(f"/proc/self/task/{tid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return float("nan")
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure_cycles(mode: str, port: int, broker: int, rows: int, cycles: int) -> None:
    """``cycles`` poll cycles and out (under callgrind): the engine pauses after them."""
    from rac_console.commands.plant import parse_mqtt_address
    from rac_console.engine import Engine, EngineOptions
    from rac_console.plant.metrics import MetricsBoard

    options = EngineOptions(
        interval=0.0,
        frames=False,
        max_cycles=cycles,
        publish=parse_mqtt_address(f"mqtt://{HOST}:{broker}/{PREFIX}") if mode == "mqtt" else None,
        metrics=MetricsBoard() if mode == "metrics" else None,
        plant_name="rc8",
    )
    engine = Engine(HOST, port, options=options)
    engine.start()
    tap = engine._publisher.tap
    feed = tap.mqtt if tap is not None else None
    while feed is not None and not feed.connected:
        time.sleep(0.01)
    engine.submit(f"watch I 0-{rows - 1}")
    poller = engine._poller
    while poller.cycles_done < cycles:
        time.sleep(0.01)
        engine.outbox.drain()
    engine.stop()  # the feed hands over what is pending, then says offline
    os._exit(0)


# ------------------------------------------------------------------ the broker


class Mosquitto:
    """mosquitto on 127.0.0.1 and a free port, in ``folder``, until :meth:`stop`."""

    def __init__(self, folder: Path, cpu: int | None) -> None:
        path = shutil.which("mosquitto") or shutil.which(
            "mosquitto", path="/usr/sbin:/usr/local/sbin"
        )
        if path is None:
            raise SystemExit("mosquitto is not installed: nothing to publish to")
        with socket.socket() as sock:
            sock.bind((HOST, 0))
            self.port = int(sock.getsockname()[1])
        config = folder / "mosquitto.conf"
        config.write_text(
            f"listener {self.port} {HOST}\npersistence false\nallow_anonymous true\n"
            f"user {getpass.getuser()}\n"
        )
        self.log = folder / "mosquitto.log"
        with self.log.open("ab") as log:
            self.process = subprocess.Popen(
                [path, "-c", str(config)],
                stdout=log,
                stderr=subprocess.STDOUT,
                preexec_fn=(lambda: os.sched_setaffinity(0, {cpu})) if cpu is not None else None,
            )
        until = time.monotonic() + 10
        while True:
            if self.process.poll() is not None:
                raise SystemExit(f"mosquitto ended: {self.log.read_text()[-2000:]}")
            try:
                socket.create_connection((HOST, self.port), timeout=0.5).close()
                return
            except OSError:
                if time.monotonic() > until:
                    raise SystemExit("mosquitto did not listen in time") from None
                time.sleep(0.05)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(10)


# ------------------------------------------------------------------ the parent


def run_child(args: list[object], cpu: int | None, timeout: float) -> dict[str, float]:
    result = subprocess.run(
        [sys.executable, __file__, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
        preexec_fn=(lambda: os.sched_setaffinity(0, {cpu})) if cpu is not None else None,
    )
    if result.returncode != 0:
        raise RuntimeError(f"{args} failed:\n{result.stderr[-3000:]}")
    out: dict[str, float] = json.loads(result.stdout.strip().splitlines()[-1])
    return out


def callgrind_per_poll(
    plant: str, port: int, broker: int, rows: int, cycles: int, cpu: int | None, old: Path | None
) -> float:
    """Instructions per poll: callgrind's totals for ``cycles`` and ``2 x cycles`` poll
    cycles, the difference over the extra polls."""
    mode, _, is_old = plant.partition("-")
    package = ["--package", str(old)] if is_old and old is not None else []

    def total(count: int) -> int:
        with tempfile.TemporaryDirectory() as folder:
            out = Path(folder) / "callgrind.out"
            subprocess.run(
                ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
                 __file__, "--cycles", mode, str(port), str(broker), str(rows), str(count),
                 *package],
                capture_output=True,
                timeout=3600,
                check=False,
                preexec_fn=(lambda: os.sched_setaffinity(0, {cpu})) if cpu is not None else None,
            )  # fmt: skip
            found = 0
            for path in Path(folder).glob("callgrind.out*"):
                match = re.search(r"^(?:summary|totals):\s+(\d+)", path.read_text(), re.M)
                if match:
                    found += int(match.group(1))
            return found

    small, large = total(cycles), total(2 * cycles)
    return (large - small) / (cycles * rows) if small and large else float("nan")


def spread(values: list[float], form: str) -> str:
    return f"[{form.format(min(values))}-{form.format(max(values))}]"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--warm", type=float, default=1.0)
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--placement", choices=("pinned", "free"), default="pinned")
    parser.add_argument("--callgrind", action="store_true")
    parser.add_argument("--callgrind-cycles", type=int, default=20)
    parser.add_argument("--quick", action="store_true", help="one short round: checks it runs")
    parser.add_argument("--old", type=Path, help="another checkout's package beside this one")
    parser.add_argument("--package", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--measure", nargs=4, metavar=("MODE", "PORT", "BROKER", "ROWS"))
    parser.add_argument("--cycles", nargs=5, metavar=("MODE", "PORT", "BROKER", "ROWS", "N"))
    args = parser.parse_args()
    if args.package is not None:  # a measuring child of --old's package
        sys.path.insert(0, str(args.package.resolve()))
    if args.measure:
        mode, port, at, rows = args.measure
        measure(mode, int(port), int(at), int(rows), args.seconds, args.warm)
        return 0
    if args.cycles:
        mode, port, at, rows, count = args.cycles
        measure_cycles(mode, int(port), int(at), int(rows), int(count))
        return 0
    if args.quick:
        args.rounds, args.seconds, args.warm, args.callgrind_cycles = 1, 0.5, 0.3, 2

    cpus = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    engine_cpu: int | None = None
    broker_cpu: int | None = None
    if args.placement == "pinned" and len(cpus) >= 2:
        engine_cpu, broker_cpu = cpus[-1], cpus[-2]
    placement = (
        f"engine + responder on CPU {engine_cpu}, mosquitto on CPU {broker_cpu}"
        if engine_cpu is not None
        else "free (wherever the scheduler puts them)"
    )
    plants = [*MODES, *(f"{mode}-old" for mode in MODES[1:] if args.old is not None)]
    programs = CPrograms()
    if programs.responder is None:
        print(f"cannot measure: {programs.error}")
        return 1
    folder = tempfile.TemporaryDirectory(prefix="rac-plant-bench-")
    responders: dict[str, Server] = {}
    broker: Mosquitto | None = None
    sent: dict[str, list[float]] = {}
    on_engine: dict[str, list[float]] = {}  # the engine's thread's µs CPU per poll
    try:
        broker = Mosquitto(Path(folder.name), broker_cpu)
        for values in VALUES:
            extra = ["changing"] if values == "changing" else []
            responders[values] = Server([str(programs.responder), "0", *extra], engine_cpu)
        assert broker is not None
        broker_port = broker.port

        def side(values: str, plant: str) -> Callable[[], Run]:
            mode, _, old = plant.partition("-")
            package = ["--package", args.old] if old else []

            def run() -> Run:
                out = run_child(
                    ["--measure", mode, responders[values].port, broker_port, args.rows,
                     "--seconds", args.seconds, "--warm", args.warm, *package],
                    engine_cpu,
                    timeout=args.seconds + args.warm + 120,
                )  # fmt: skip
                sent.setdefault(f"{values} {plant}", []).append(out["sent"] / out["seconds"])
                on_engine.setdefault(f"{values} {plant}", []).append(
                    out["engine"] / out["requests"] * 1e6 if out["requests"] else float("nan")
                )
                return Run(out["requests"], out["seconds"], out["cpu"])

            return run

        load = " ".join(f"{x:.2f}" for x in os.getloadavg())
        print(f"# {os.cpu_count()} CPUs, load average {load} at the start; {placement}")
        sides = {f"{v} {m}": side(v, m) for v in VALUES for m in plants}
        results = alternate(args.rounds, sides)
        instructions: dict[str, float] = {}
        if args.callgrind and shutil.which("valgrind"):
            for values in VALUES:
                for plant in plants:
                    instructions[f"{values} {plant}"] = callgrind_per_poll(
                        plant, responders[values].port, broker_port, args.rows,
                        args.callgrind_cycles, engine_cpu, args.old,
                    )  # fmt: skip
        elif args.callgrind:
            print("(no valgrind on PATH: no instruction counts)")
    finally:
        for responder in responders.values():
            responder.stop()
        if broker is not None:
            broker.stop()
        folder.cleanup()
        programs.cleanup()
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(
        f"\n{args.rounds} round{'s' * (args.rounds != 1)} of {args.seconds:g} s, "
        f"watch I 0-{args.rows - 1} at interval 0 against the C responder; "
        f"medians [min-max]; load average {load} at the end"
    )
    print(
        f"{'values':<11} {'plant':<11} {'polls/s [min-max]':<26} {'µs CPU/poll':>11} "
        f"{'engine':>7}  "
        f"{'msgs acked/s [min-max]':<24} {'/ off [min-max]':<18} goal"
    )
    for values in VALUES:
        off = results[f"{values} off"]
        for mode in plants:
            runs = results[f"{values} {mode}"]
            rates = [run.rate for run in runs]
            cpu = statistics.median(run.cpu_us for run in runs)
            acked = sent[f"{values} {mode}"]
            shown_sent = (
                f"{statistics.median(acked):>7,.0f} {spread(acked, '{:,.0f}')}"
                if mode.startswith("mqtt")
                else "-"
            )
            if mode == "off":
                shown_ratio, goal = "-", ""
            else:
                ratios = [a.rate / b.rate for a, b in zip(runs, off, strict=True)]
                ratio = statistics.median(ratios)
                shown_ratio = f"{ratio:.2f} {spread(ratios, '{:.2f}')}"
                goal = f">= {GOAL}: {'met' if ratio >= GOAL else 'NOT met'}"
            shown_rate = f"{statistics.median(rates):>7,.0f} {spread(rates, '{:,.0f}')}"
            engine = statistics.median(on_engine[f"{values} {mode}"])
            print(
                f"{values:<11} {mode:<11} {shown_rate:<26} {cpu:>11.1f} {engine:>7.1f}  "
                f"{shown_sent:<24} {shown_ratio:<18} {goal}"
            )
    if instructions:
        print(
            f"\ninstructions per poll (callgrind, {args.callgrind_cycles} more cycles; "
            "changing mqtt: about a message a poll under callgrind, an upper bound)"
        )
        for values in VALUES:
            off_count = instructions[f"{values} off"]
            for mode in plants:
                count = instructions[f"{values} {mode}"]
                print(
                    f"{values:<11} {mode:<11} {count:>12,.0f}"
                    + (f"   / off {count / off_count:.2f}" if mode != "off" else "")
                )
    print(
        "\nµs CPU/poll: the whole process (every thread); engine: the engine's thread alone "
        "(/proc, 10 ms ticks).\nmqtt: to mosquitto on 127.0.0.1 (retained, QoS 1), msgs "
        "acked/s = MqttFeed.sent over the window.\nmetrics: the MetricsBoard written by the "
        "engine, no HTTP server and no scrape (the engine's side of --metrics)."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
