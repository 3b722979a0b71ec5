"""How long ``EXE --version`` takes to start and end, each EXE run N times in turn (run
under the Windows CPython: ``scripts/windows-python scripts/windows/start_times.py N
LABEL=EXE ...``). Prints, per label, every time and the median, in milliseconds: the
process is started from Windows itself, so Wine's own start is not counted."""

from __future__ import annotations

import statistics
import subprocess
import sys
import time


def main() -> int:
    runs, *named = sys.argv[1:]
    times: dict[str, list[float]] = {label: [] for label, _ in (n.split("=", 1) for n in named)}
    for _ in range(int(runs)):
        for label, exe in (n.split("=", 1) for n in named):  # in turn: the same disk cache
            began = time.perf_counter()
            subprocess.run([exe, "--version"], capture_output=True, check=True)
            times[label].append((time.perf_counter() - began) * 1000)
    for label, taken in times.items():
        shown = " ".join(f"{t:.0f}" for t in taken)
        print(f"{label}: --version median {statistics.median(taken):.0f} ms ({shown})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
