"""A served session's memory after a flood of keys, and whether it still answers.

    python benchmarks/serve_keys.py [--kib 1024] [--chunk 8000] [--seconds 120]
                                    [--stop-at-mb 4000] [--code DIR]

Runs ``rac-console serve`` (from the source folder ``--code`` when given: the code
before a change, checked out in a worktree), opens one session as a browser does
(``tests/support/serving.py``), reads its console's resident memory (``/proc``), then
sends ``--kib`` KiB of ``a`` typed as keys (``["stdin", "aaa…"]``, ``--chunk``
characters a message), and every 0.5 s a Ctrl+U and ``get I 1`` until the console answers
it. It prints the memory before, the most seen and the memory once answered, and how
long the answer took; a console that has not answered after ``--seconds``, or whose
memory passed ``--stop-at-mb``, is stopped there and said so.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the tests' browser: tests.support

from tests.support.drivers import Running  # noqa: E402
from tests.support.serving import consoles_of, open_console, start_serve  # noqa: E402


def rss_mb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) // 1024
    return 0


def measure(env: dict[str, str], args: argparse.Namespace) -> str:
    running: list[Running] = []
    try:
        served = start_serve(env, running)
        console = open_console(served)
        console.until("SERVED", "connected")
        (pid,) = consoles_of(served.running.process.pid)
        before = most = rss_mb(pid)
        total, started = args.kib * 1024, time.monotonic()
        for at in range(0, total, args.chunk):
            console.send("stdin", "a" * min(args.chunk, total - at))
        answered = None
        while answered is None and time.monotonic() - started < args.seconds:
            console.send("stdin", "\x15")  # Ctrl+U: the line emptied
            console.type_line("get I 1")
            with contextlib.suppress(AssertionError):
                console.until("I1 = 1", deadline=0.5)
                answered = time.monotonic() - started
            most = max(most, rss_mb(pid))
            if most > args.stop_at_mb:
                break
        now = rss_mb(pid)
        if answered is not None:
            end = f"get answered after {answered:.1f} s"
        else:
            end = f"no answer, stopped after {time.monotonic() - started:.0f} s"
        return (
            f"| {args.kib:,} KiB as keys | {before} MB | {max(most, now):,} MB | {now:,} MB "
            f"| {end} |"
        )
    finally:
        for run in running:
            run.process.kill()
            run.process.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kib", type=int, default=1024)
    parser.add_argument("--chunk", type=int, default=8000)
    parser.add_argument("--seconds", type=float, default=120.0)
    parser.add_argument("--stop-at-mb", type=int, default=4000)
    parser.add_argument("--code", type=Path, help="the source folder to serve from")
    args = parser.parse_args()
    home = Path(os.environ.get("TMPDIR", "/tmp")) / f"serve-keys-{os.getpid()}"
    home.mkdir(exist_ok=True)
    env = dict(os.environ) | {"HOME": str(home), "XDG_CONFIG_HOME": str(home / "config"),
                              "XDG_STATE_HOME": str(home / "state")}  # fmt: skip
    if args.code is not None:
        env["PYTHONPATH"] = str(args.code.resolve())
    print("| typed | console before | most seen | once answered | the `get` after |")
    print("|---|--:|--:|--:|---|")
    print(measure(env, args), flush=True)


if __name__ == "__main__":
    main()
