"""The CLI's ``watch`` memory over a long run: RSS sampled while it polls flat out.

    python benchmarks/watch_memory.py [SECONDS] [EVERY] [--json=FILE]

Starts the built-in simulator (``rac-console sim``) in a process of its own, then
``rac-console -H 127.0.0.1 -p PORT watch I 0-99 --every 0 --json`` with its lines
read and thrown away as a reader of a pipe would. Prints the RSS (from
``/proc/PID/status``, VmRSS) every EVERY seconds (default 30), and at the end the
RSS after 10 s, the last one, their ratio and the cycles read. The goal: within 10 %
of the 10 s figure after 10 minutes (SECONDS=600, the default).
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import threading
import time
from pathlib import Path


def rss_kib(pid: int) -> int:
    with open(f"/proc/{pid}/status", encoding="ascii") as status:
        match = re.search(r"^VmRSS:\s+(\d+) kB", status.read(), re.MULTILINE)
    return int(match.group(1)) if match else 0


def main() -> None:
    words = [w for w in sys.argv[1:] if not w.startswith("--json=")]
    out = next((w[7:] for w in sys.argv[1:] if w.startswith("--json=")), None)
    seconds = float(words[0]) if words else 600.0
    every = float(words[1]) if len(words) > 1 else 30.0
    python = sys.executable
    sim = subprocess.Popen(
        [python, "-m", "rac_console", "sim", "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        assert sim.stdout is not None
        port = None
        for line in sim.stdout:
            found = re.search(r":(\d+)\b", line)
            if found:
                port = int(found.group(1))
                break
        assert port is not None, "the simulator did not say its port"
        watch = subprocess.Popen(
            [
                python,
                "-m",
                "rac_console",
                "-H",
                "127.0.0.1",
                "-p",
                str(port),
                "--json",
                "watch",
                "I",
                "0-99",
                "--every",
                "0",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
        )
        cycles = 0

        def read() -> None:
            nonlocal cycles
            assert watch.stdout is not None
            for _ in watch.stdout:
                cycles += 1

        threading.Thread(target=read, daemon=True).start()
        started = time.monotonic()
        at_10: int | None = None
        next_print = every
        last = 0
        while (elapsed := time.monotonic() - started) < seconds:
            time.sleep(1)
            last = rss_kib(watch.pid)
            if at_10 is None and elapsed >= 10:
                at_10 = last
                print(f"{elapsed:6.0f} s  RSS {last / 1024:7.1f} MiB  cycles {cycles}  (the base)")
            if elapsed >= next_print:
                print(f"{elapsed:6.0f} s  RSS {last / 1024:7.1f} MiB  cycles {cycles}")
                next_print += every
        watch.terminate()
        watch.wait(10)
        assert at_10 is not None
        print(
            f"after 10 s {at_10 / 1024:.1f} MiB, after {seconds:.0f} s {last / 1024:.1f} MiB: "
            f"{last / at_10:.3f}x, {cycles} cycles ({cycles * 100} reads)"
        )
        if out is not None:
            figures = {"rss_10s_mib": at_10 / 1024, "rss_end_mib": last / 1024}
            Path(out).write_text(json.dumps(figures | {"ratio": last / at_10}) + "\n")
    finally:
        sim.terminate()
        sim.wait(10)


if __name__ == "__main__":
    main()
