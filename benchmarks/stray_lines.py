"""Stray lines: how often a line nobody asked for is reported as a value.

    python benchmarks/stray_lines.py [--count 1000] [--placements ...] [--json FILE]

For each mode the simulator runs in its own process, as a controller would:
``rac-console sim --port 0 --extra-every 1 [--extra-gap MS]``, so every reply is
followed by the stray line ``0,3,424242``:

  - same write:  the stray in the reply's own write (the simulator's default);
  - gap 0:       the stray as a write of its own, straight after the reply;
  - 5 ms later:  the stray as a write of its own 5 ms after the reply.

One blocking :class:`rac_console.session.Session` then makes COUNT GETs of I10 (set
to 123 beforehand, never the stray's value) back to back, and the script counts
answers that are right, answers reported OK with a wrong value, connection resets,
and errors. It prints figures; it asserts nothing.

Each mode runs under up to three CPU placements (Linux, two CPUs or more): wherever
the scheduler puts the two processes; the client and the simulator on different CPUs
(as with a controller that is another machine); both on one CPU. On one CPU the reply's
write wakes the client, which can run its whole turn (read, check, send the next
request) before the simulator gets the CPU back to make its second write.

A stray that arrives after the next request left cannot be told from its answer (the
protocol has no request ids): that residual is what the 5 ms mode, and the one-CPU
placement, show.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from sim_harness import SimulatorProcess

from rac_console.protocol import Variant, kind_of
from rac_console.session import Frame, Session, TransportError

INT = kind_of("I")
INDEX, VALUE = 10, 123
MODES = {"same write": None, "gap 0": 0.0, "5 ms later": 5.0}
TARGET_WRONG_OK = 0.01  # at most 1% wrong-OK when the stray comes straight after the reply
PLACEMENTS = ("scheduler", "apart", "together")


@dataclass
class Tally:
    mode: str
    placement: str
    gets: int = 0
    right: int = 0
    wrong_ok: int = 0
    resets: int = 0  # connections dropped and reopened
    unsolicited_frames: int = 0
    waiting_at_send: int = 0  # times something was already in the receive buffer
    errors: dict[str, int] = field(default_factory=dict)


def cpus_for(placement: str) -> tuple[int, int] | None:
    """(client CPU, simulator CPU) for a placement; None: leave it to the scheduler."""
    if placement == "scheduler":
        return None
    first, second = sorted(os.sched_getaffinity(0))[:2]
    return (first, second) if placement == "apart" else (first, first)


def available_placements() -> list[str]:
    pinnable = hasattr(os, "sched_setaffinity") and len(os.sched_getaffinity(0)) >= 2
    return list(PLACEMENTS) if pinnable else ["scheduler"]


def start_simulator(gap: float | None, cpu: int | None) -> SimulatorProcess:
    """``rac-console sim --port 0 --extra-every 1 [--extra-gap MS]``, pinned to ``cpu``."""
    args = ["--extra-every", "1"]
    if gap is not None:
        args += ["--extra-gap", f"{gap:g}"]
    pin = None if cpu is None else (lambda: os.sched_setaffinity(0, {cpu}))
    return SimulatorProcess(*args, preexec=pin)


def measure(mode: str, placement: str, port: int, count: int) -> Tally:
    tally = Tally(mode, placement)
    errors: Counter[str] = Counter()
    with Session("127.0.0.1", port) as session:
        # The stray is switched off while the variable is set, then on again.
        session.send_raw("SIM:SET:extra_every=0")
        session.put(INT, INDEX, Variant(3, VALUE))
        session.send_raw("SIM:SET:extra_every=1")
        frames: list[Frame] = []
        opened: list[str] = []
        session.add_frame_observer(frames.append)
        session.add_state_observer(
            lambda state: opened.append(state) if state == "connected" else None
        )
        for _ in range(count):
            tally.gets += 1
            # Peeked without reading: did bytes already wait before this GET?
            tally.waiting_at_send += session.has_unread()
            try:
                reply = session.get(INT, INDEX)
            except TransportError as exc:
                errors[type(exc).__name__] += 1
                continue
            if not reply.response.ok:
                errors[reply.response.name or hex(reply.response.code)] += 1
            elif reply.response.variant is not None and reply.response.variant.value == VALUE:
                tally.right += 1
            else:
                tally.wrong_ok += 1
        tally.resets = len(opened)
        tally.unsolicited_frames = sum(f.unsolicited for f in frames)
    tally.errors = dict(errors)
    return tally


def run_mode(mode: str, gap: float | None, placement: str, count: int) -> Tally:
    cpus = cpus_for(placement)
    everywhere = os.sched_getaffinity(0) if cpus is not None else None
    simulator = start_simulator(gap, cpus[1] if cpus else None)
    try:
        if cpus is not None:
            os.sched_setaffinity(0, {cpus[0]})
        return measure(mode, placement, simulator.port, count)
    finally:
        if everywhere is not None:
            os.sched_setaffinity(0, everywhere)
        simulator.stop()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=1000, help="GETs per mode (default 1000)")
    parser.add_argument(
        "--placements",
        nargs="+",
        choices=PLACEMENTS,
        default=available_placements(),
        help="CPU placements to run (default: all this machine allows)",
    )
    parser.add_argument("--json", metavar="FILE", help="also write the figures to FILE")
    args = parser.parse_args()
    tallies = [
        run_mode(mode, gap, placement, args.count)
        for placement in args.placements
        for mode, gap in MODES.items()
    ]
    print(
        f"{args.count} GETs of I{INDEX} (= {VALUE}) per row; a stray 0,3,424242 after every reply"
    )
    print(
        f"{'placement':<10} {'mode':<11} {'right':>6} {'wrong OK':>9} {'rate':>6} "
        f"{'resets':>7} {'in buffer':>10}  errors"
    )
    for t in tallies:
        rate = t.wrong_ok / t.gets if t.gets else 0.0
        errors = ", ".join(f"{name} {n}" for name, n in sorted(t.errors.items())) or "none"
        print(
            f"{t.placement:<10} {t.mode:<11} {t.right:>6} {t.wrong_ok:>9} {rate:>6.1%} "
            f"{t.resets:>7} {t.waiting_at_send:>10}  {errors}"
        )
    print(
        "in buffer: GETs made while bytes already waited in the receive buffer (the check "
        "catches these); resets: connections dropped and reopened"
    )
    for t in tallies:
        if t.mode == "gap 0":
            met = "met" if t.wrong_ok <= TARGET_WRONG_OK * t.gets else "NOT met"
            print(f"target, gap 0, {t.placement}: at most {TARGET_WRONG_OK:.0%} wrong OK: {met}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump([asdict(t) for t in tallies], out, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
