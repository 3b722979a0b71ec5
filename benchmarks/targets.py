"""Every performance target, measured in one run, an older package beside this one.

    python benchmarks/targets.py [--old DIR] [--rounds 20] [--memory-seconds 600]
                                 [--callgrind] [--smoke] [--json FILE]

Runs, in turn, each benchmark that owns a figure, each printing its own table with the
spread over its rounds (old and new side by side where the figure is the client's):

1. ``floor.py``: the session (``get``, ``exchange``, ``latency``), ``execute()`` and the
   engine's poller against a bare socket loop, one CPU, a C responder; with
   ``--callgrind`` instructions per request as well;
2. ``startup.py``: ``--version``, a one-shot ``get``, the console's first paint beside a
   minimal Textual app's, and what a ``get`` imports;
3. ``console_keys.py``: key to screen in tmux with 200 rows polled flat out, and the
   console's poll rate against the session's;
4. ``sim_throughput.py``: the simulator against the C epoll responder, 50 sessions;
5. memory: the console over 10k and ``--frames`` frames (``console_bench.py``), and
   ``rac-console watch I 0-99 --every 0`` over ``--memory-seconds`` (``watch_memory.py``).

Then one table: each figure, old and new, its target and whether the new one meets it.
``--smoke`` runs every step at tiny sizes (a check that it runs, not a measurement).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

#: (figure, key in the merged figures (``{old,new}.`` added where both exist), target
#: text, check of the new value, format)
Target = tuple[str, str, str, Callable[[float], bool], str]


def at_least(goal: float) -> Callable[[float], bool]:
    return lambda value: value >= goal


def at_most(goal: float) -> Callable[[float], bool]:
    return lambda value: value <= goal


def shown(_: float) -> bool:
    return True


R, MS, N = "{:.2f}", "{:.0f} ms", "{:,.0f}"
TARGETS: list[Target] = [
    ("Session.get: rate / bare loop", "get.rate_to_bare", ">= 0.85", at_least(0.85), R),
    ("Session.get: CPU / bare loop", "get.cpu_to_bare", "<= 1.25", at_most(1.25), R),
    ("Session.exchange: rate / bare", "exchange.rate_to_bare", ">= 0.85", at_least(0.85), R),
    ("Session.exchange: CPU / bare", "exchange.cpu_to_bare", "<= 1.25", at_most(1.25), R),
    ("latency: rate / bare", "latency.rate_to_bare", ">= 0.85", at_least(0.85), R),
    ("latency: CPU / bare", "latency.cpu_to_bare", "<= 1.25", at_most(1.25), R),
    ("execute(): rate / bare", "execute.rate_to_bare", ">= 0.75", at_least(0.75), R),
    ("engine poller: rate / Session.get", "engine.rate_to_get", ">= 0.80", at_least(0.8), R),
    ("Session.get: instructions/request", "get.instructions", "reported", shown, N),
    ("bare loop: instructions/request", "bare.instructions", "reported", shown, N),
    ("execute(): instructions/request", "execute.instructions", "reported", shown, N),
    ("engine: instructions/poll", "engine.instructions", "reported", shown, N),
    ("console, 200 rows flat out: key p95", "keys.p95_ms", "<= 50 ms", at_most(50), MS),
    ("console, 200 rows: polls / session", "keys.poll_ratio", ">= 0.5", at_least(0.5), R),
    ("console first paint / minimal app", "paint_ratio", "<= 1.3", at_most(1.3), R),
    ("get I 1, one-shot", "get_ms", "<= 120 ms", at_most(120), MS),
    ("--version", "version_ms", "<= 60 ms", at_most(60), MS),
    ("simulator / C epoll, 50 sessions", "sim_to_c_50", ">= 0.70", at_least(0.7), R),
    ("  the same with uvloop (the [fast] extra)", "uvloop.sim_to_c_50", "reported", shown, R),
    ("console memory: end / 10k frames", "console_memory_ratio", "<= 1.10", at_most(1.1), R),
    ("CLI watch memory: end / 10 s", "watch_memory_ratio", "<= 1.10", at_most(1.1), R),
]


def step(title: str, command: list[str], out: Path | None, timeout: float) -> dict[str, object]:
    """Run one benchmark, its output shown as it comes; its figures (JSON) if any."""
    print(f"\n## {title}\n$ {' '.join(command)}", flush=True)
    started = time.monotonic()
    try:
        subprocess.run(command, cwd=HERE, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        print(f"(stopped after {timeout:.0f} s)")
    print(f"# {time.monotonic() - started:.0f} s", flush=True)
    if out is None or not out.exists() or not out.read_text().strip():
        return {}
    figures = json.loads(out.read_text())
    return figures if isinstance(figures, dict) else {}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, help="a checkout of the old package (read only)")
    parser.add_argument("--rounds", type=int, default=20)
    parser.add_argument("--memory-seconds", type=float, default=600.0)
    parser.add_argument("--frames", type=int, default=1_000_000)
    parser.add_argument("--callgrind", action="store_true")
    parser.add_argument("--uvloop", type=Path, help="a folder with uvloop: the simulator on it too")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: checks it runs")
    parser.add_argument("--json", type=Path, help="write every figure here too")
    args = parser.parse_args()
    if args.smoke:
        args.rounds, args.memory_seconds, args.frames = 1, 12.0, 12_000
    python = sys.executable
    old = ["--old", str(args.old)] if args.old else []
    package = ["--package", str(args.old)] if args.old else []
    figures: dict[str, object] = {}
    print(f"# {os.cpu_count()} CPUs, load {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)

        def out(name: str) -> Path:
            return tmp / f"{name}.json"

        requests = "200" if args.smoke else "2000"
        floor = [python, "floor.py", "--rounds", str(args.rounds), "--requests", requests]
        floor += old + (["--callgrind"] if args.callgrind else []) + ["--json", str(out("floor"))]
        for key, value in step("the client against its floor", floor, out("floor"), 7200).items():
            name, _, figure = key.partition(".")  # new.get.rate_to_bare
            figures[f"{name}.{figure}"] = value
        for name in ("old", "new"):
            engine, get = figures.get(f"{name}.engine.per_s"), figures.get(f"{name}.get.per_s")
            if isinstance(engine, float) and isinstance(get, float):
                figures[f"{name}.engine.rate_to_get"] = engine / get

        runs = "1" if args.smoke else "15"
        startup = [python, "startup.py", "--runs", runs, *package, "--json", str(out("startup"))]
        figures |= step("start-up", startup, out("startup"), 1800)

        if (HERE / "console_keys.py").exists():
            keys = [python, "console_keys.py", *package, "--json", str(out("keys"))]
            keys += ["--smoke"] if args.smoke else []
            for key, value in step("console keys", keys, out("keys"), 1800).items():
                name, _, figure = key.partition(".")
                figures[f"{name}.keys.{figure}"] = value

        seconds = "0.3" if args.smoke else "2"
        sim = [python, "sim_throughput.py", "--sessions", "50", "--seconds", seconds]
        sim += ["--rounds", "1" if args.smoke else "7", "--json", str(out("sim"))]
        figures |= {f"new.{k}": v for k, v in step("simulator", sim, out("sim"), 1800).items()}
        if args.uvloop:
            sim_uv = [*sim[:-1], str(out("sim-uv")), "--pythonpath", str(args.uvloop)]
            found = step("simulator on uvloop", sim_uv, out("sim-uv"), 1800)
            figures |= {f"new.uvloop.{k}": v for k, v in found.items()}
        if args.old:
            sim_old = [*sim[:-1], str(out("sim-old")), "--pythonpath", str(args.old)]
            found = step("simulator (old package)", sim_old, out("sim-old"), 1800)
            figures |= {f"old.{k}": v for k, v in found.items()}

        soak = [python, "console_bench.py", "--rounds", "1", "--seconds", "0.5"]
        soak += ["--frames", str(args.frames), "--json", str(out("soak"))]
        found = step("console memory", soak, out("soak"), 3600)
        after, at_10k = found.get("memory_after_mb"), found.get("memory_10k_frames_mb")
        if isinstance(after, float) and isinstance(at_10k, float) and at_10k:
            figures["new.console_memory_ratio"] = after / at_10k

        watch = [python, "watch_memory.py", str(args.memory_seconds), "60"]
        found = step("CLI watch memory", [*watch, f"--json={out('watch')}"], out("watch"), 7200)
        if isinstance(found.get("ratio"), float):
            figures["new.watch_memory_ratio"] = found["ratio"]
    print("\n" + "\n".join(table(figures, bool(args.old))))
    if args.json is not None:
        args.json.write_text(json.dumps(figures, indent=2) + "\n", encoding="utf-8")


def table(figures: dict[str, object], with_old: bool) -> list[str]:
    """The targets as a Markdown table (the README's is made from it)."""
    rows = ["| figure | " + ("old | " if with_old else "") + "new | target | met |"]
    rows.append("|---|" + ("---:|" if with_old else "") + "---:|---|---|")
    for label, key, target, check, form in TARGETS:
        new, was = figures.get(f"new.{key}"), figures.get(f"old.{key}")
        shown_new = form.format(new) if isinstance(new, float | int) else "–"
        shown_old = form.format(was) if isinstance(was, float | int) else "–"
        met = ("yes" if check(float(new)) else "NO") if isinstance(new, float | int) else "–"
        if target == "reported":
            met = ""
        rows.append(
            f"| {label} | "
            + (f"{shown_old} | " if with_old else "")
            + f"{shown_new} | {target} | {met} |"
        )
    return rows


if __name__ == "__main__":
    main()
