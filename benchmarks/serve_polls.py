"""A served session's poll load, seen by its controller.

    python benchmarks/serve_polls.py [--seconds 6]

Each case runs ``rac-console -H 127.0.0.1:PORT serve`` (with the case's
``--min-interval`` and ``--max-rows``) against a recording controller of the tests
(``tests/support/servers.py``, every GET answered), opens one session as a browser does
(``tests/support/serving.py``), types the case's ``watch I A-B`` lines (256 rows each)
and ``interval S``, lets it settle 3 s, then counts for ``--seconds``: the GETs that
reached the controller a second, the distinct variables asked for, and the CPU of the
session's console process (``/proc``). The first case is one session asking for 4,096
rows back to back with the bounds lifted (as before they existed); the next, the same
asked within the defaults; the others, what the operator could allow.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the tests' controller and browser: tests.support

from tests.support.drivers import Running  # noqa: E402
from tests.support.servers import RecordingServer, sample_reply  # noqa: E402
from tests.support.serving import consoles_of, open_console, start_serve  # noqa: E402

#: (rows asked for, interval typed, serve's options)
LIFTED = ("--min-interval", "0", "--max-rows", "4096")
CASES = [
    (4096, 0.0, LIFTED),
    (4096, 0.0, ()),
    (256, 0.5, LIFTED),
    (256, 0.2, LIFTED),
    (256, 0.1, LIFTED),
    (1024, 0.5, LIFTED),
]


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure(env: dict[str, str], rows: int, interval: float, options: tuple[str, ...],
            seconds: float) -> str:  # fmt: skip
    controller = RecordingServer(sample_reply)
    running: list[Running] = []
    try:
        where = ("-H", f"127.0.0.1:{controller.port}")
        served = start_serve(env, running, *options, before=where)
        console = open_console(served, 160, 50)
        console.until("SERVED", "connected")
        for first in range(0, rows, 256):
            console.type_line(f"watch I {first}-{min(first + 255, rows - 1)}")
        console.type_line(f"interval {interval:g}")
        console.until(f"interval {interval:g}")
        time.sleep(3)  # the watch and the interval taken, polling in its stride
        (pid,) = consoles_of(served.running.process.pid)
        since, cpu, started = len(controller.lines), cpu_seconds(pid), time.monotonic()
        while time.monotonic() - started < seconds:  # the screen read, as a browser does
            with contextlib.suppress(AssertionError):
                console.until("never on the screen", deadline=0.5)
        lines, took = controller.lines[since:], time.monotonic() - started
        used = cpu_seconds(pid) - cpu
        console.close()
        lifted = "lifted" if options else "defaults"
        return (
            f"| {rows:,} rows, interval {interval:g}, bounds {lifted} | {len(set(lines)):,} "
            f"| {len(lines) / took:,.0f} | {100 * used / took:.0f} % |"
        )
    finally:
        for run in running:
            run.process.kill()
            run.process.wait()
        controller.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=6.0)
    args = parser.parse_args()
    home = Path(os.environ.get("TMPDIR", "/tmp")) / f"serve-polls-{os.getpid()}"
    home.mkdir(exist_ok=True)
    env = dict(os.environ) | {"HOME": str(home), "XDG_CONFIG_HOME": str(home / "config"),
                              "XDG_STATE_HOME": str(home / "state")}  # fmt: skip
    print("| asked | rows polled | GETs/s at the controller | session's console CPU |")
    print("|---|--:|--:|--:|")
    for rows, interval, options in CASES:
        print(measure(env, rows, interval, options, args.seconds), flush=True)


if __name__ == "__main__":
    main()
