"""The console an integrator keeps open all shift, polled flat out.

    python benchmarks/shift_bench.py [--seconds 3] [--rounds 5] [--against sim|c|both]
                                     [--placement same|apart|free] [--json FILE]

300 watched variables: IO 0-255 shown in the I/O grid (F5), P 0-19 with their
sparklines, I 0-23; interval 0 (polls back to back). In one run, alternating the sides
each round so machine noise mostly cancels, against the simulator (``rac-console sim``
in its own process, as the issue asks) and/or the C responder (the floor, which hides
nothing of the client's cost):

  - the session client alone (``Session.get`` in a loop, no UI);
  - the console as above: polls/s and its ratio to the session client (target >= 0.8),
    key-to-screen median and p95 (target p95 <= 50 ms), CPU per poll;
  - the same console logging every cycle to a CSV file: CPU per poll, and what the log
    adds (target <= 10 %).
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from pathlib import Path

from bench_common import CPrograms, Run, child_run, pinned, placement_cpus, start_responder
from console_bench import console_round, key_figures
from sim_harness import SimulatorProcess

WATCH = ("watch IO 0-255", "watch P 0-19", "watch I 0-23")
PRESS = ("f5",)  # the I/O grid


def measure(port: int, args: argparse.Namespace, cpu: int | None, csv_dir: str) -> dict:
    runs: dict[str, list[Run]] = {"session": [], "console": [], "console+csv": []}
    keys: list[float] = []
    for n in range(args.rounds):
        order = list(runs) if n % 2 == 0 else list(runs)[::-1]
        for side in order:
            if side == "session":
                runs[side].append(
                    child_run("bench_clients.py", "session", port, args.seconds, cpu=cpu)
                )
                continue
            csv = str(Path(csv_dir) / f"round{n}.csv") if side == "console+csv" else None
            run, out = console_round(port, args.seconds, 1.5, cpu, WATCH, PRESS, csv)
            runs[side].append(run)
            if side == "console":
                keys += out["key_ms"]
    session, console, logged = runs["session"], runs["console"], runs["console+csv"]
    ratios = sorted(c.rate / s.rate for c, s in zip(console, session, strict=True))
    csv_costs = sorted(c.cpu_us / p.cpu_us - 1 for c, p in zip(logged, console, strict=True))
    return {
        "session_rps": statistics.median(r.rate for r in session),
        "session_cpu_us": statistics.median(r.cpu_us for r in session),
        "console_polls_per_s": statistics.median(r.rate for r in console),
        "console_cpu_us": statistics.median(r.cpu_us for r in console),
        "console_to_session": statistics.median(ratios),
        "ratio_range": (ratios[0], ratios[-1]),
        "csv_polls_per_s": statistics.median(r.rate for r in logged),
        "csv_cpu_us": statistics.median(r.cpu_us for r in logged),
        "csv_cpu_added": statistics.median(csv_costs),
        "csv_added_range": (csv_costs[0], csv_costs[-1]),
        **key_figures(keys),
    }


def report(name: str, r: dict) -> None:
    print(f"\nagainst {name}")
    rows = [
        ("session client GETs/s (no UI)", f"{r['session_rps']:,.0f}",
         f"{r['session_cpu_us']:.1f} µs CPU/req"),
        ("console polls/s (300 watched, grid, sparklines)", f"{r['console_polls_per_s']:,.0f}",
         f"{r['console_cpu_us']:.1f} µs CPU/poll"),
        ("console / session (median of rounds)", f"{r['console_to_session']:.2f}",
         ">= 0.80  (rounds {:.2f}..{:.2f})".format(*r["ratio_range"])),
        ("key to screen, median ms", f"{r['key_median_ms']:.1f}", ""),
        ("key to screen, p95 ms", f"{r['key_p95_ms']:.1f}", "<= 50"),
        ("console + CSV log polls/s", f"{r['csv_polls_per_s']:,.0f}",
         f"{r['csv_cpu_us']:.1f} µs CPU/poll"),
        ("CPU per poll the CSV log adds", f"{r['csv_cpu_added'] * 100:+.1f} %",
         "<= 10 %  (rounds {:+.1f}..{:+.1f} %)".format(*(x * 100 for x in r["csv_added_range"]))),
    ]  # fmt: skip
    width = max(len(row[0]) for row in rows)
    for label, value, target in rows:
        print(f"{label:<{width}}  {value:>10}  {target}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--against", choices=("sim", "c", "both"), default="both")
    parser.add_argument("--placement", choices=("same", "apart", "free"), default="same")
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args()
    client_cpu, server_cpu = placement_cpus(args.placement)
    results: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as csv_dir:
        if args.against in ("sim", "both"):
            with SimulatorProcess(preexec=pinned(server_cpu)) as sim:
                results["simulator"] = measure(sim.port, args, client_cpu, csv_dir)
        if args.against in ("c", "both"):
            programs = CPrograms()
            server, what = start_responder(programs, server_cpu)
            try:
                results[what] = measure(server.port, args, client_cpu, csv_dir)
            finally:
                server.stop()
                programs.cleanup()
    print(f"placement {args.placement}, {args.rounds} rounds of {args.seconds:g} s")
    for name, figures in results.items():
        report(name, figures)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
