"""The console all shift: the real console in a real terminal, under a flood, for an hour.

    python benchmarks/console_soak.py [--seconds 3600] [--lose-below 0.005]
                                      [--size 120x40] [--json FILE]

The console (``python -m rac_console``, the built-in simulator) runs in a tmux session
of its own at 120x40, watching ``F 0 J 0 I 0-19 P 0 T 0`` at ``interval 0``, its frame
log on screen. Every second the screen is read (``capture-pane``): the F0 and J0 values
and the newest frame log time shown are noted with when each last changed; every 10 s a
``put I 50 N`` (N new each time) is typed and timed until its answer, ``→ N``, shows; the
console's memory (VmRSS) is read from /proc every 10 s.

``--lose-below S`` runs the console under a Textual that ends every one-shot timer
shorter than S seconds without calling it (as ``Timer._run`` does when the delay has
passed before it reads the clock): the console must not depend on one firing.

It prints: how long each of F0, J0 and the log went at most without a change, the keys'
answer times (median, p95, max) and any not answered within 30 s, the memory after the
first minute, at the end and at its highest, and how often the status line said the
screen had been behind. Targets: every gap under 4 s, every key answered within 4 s,
the memory after the first minute flat (growth under 10%).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
WATCHED = "watch F 0 J 0 I 0-19 P 0 T 0"
READ_EVERY = 1.0
KEY_EVERY = 10.0
KEY_DEADLINE = 30.0
GAP_TARGET = 4.0
MEMORY_MARKS = (1, 10, 30, 45)  # minutes at which the memory is said on the way
#: A row of the table, by its name: what follows its trend's sparkline is its value.
ROW = re.compile(r"^\W*(F0|J0)\s.*$", re.MULTILINE)
SPARKLINE = re.compile(r"[▁▂▃▄▅▆▇█]+")
#: A frame log line starts with its time of day, to the millisecond.
LOG_TIME = re.compile(r"\b(\d\d:\d\d:\d\d\.\d\d\d)\b")

#: Run as ``python -c``: the console under a Textual that loses short one-shot timers.
LOSING = """
import sys
from textual.timer import Timer
below = float(sys.argv.pop(1))
run = Timer._run
async def run_or_lose(self):
    if self._repeat == 0 and self._interval < below:
        return
    await run(self)
Timer._run = run_or_lose
from rac_console.cli.main import main
sys.exit(main())
"""


@dataclass
class Figures:
    seconds: float = 0.0
    reads: int = 0
    max_gap_s: dict[str, float] = field(default_factory=dict)
    changes: dict[str, int] = field(default_factory=dict)
    keys: int = 0
    keys_unanswered: int = 0
    key_median_ms: float = 0.0
    key_p95_ms: float = 0.0
    key_max_ms: float = 0.0
    rss_after_first_minute_mb: float = 0.0
    rss_end_mb: float = 0.0
    rss_max_mb: float = 0.0
    rss_at_minute_mb: dict[int, float] = field(default_factory=dict)
    said_behind: int = 0
    said_engine_stopped: int = 0


class Soak:
    """One console in its own tmux server."""

    def __init__(self, home: Path, size: tuple[int, int], lose_below: float | None) -> None:
        self.socket = f"rac-soak-{os.getpid()}"
        self.env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES")}
        self.env.update(
            HOME=str(home),
            XDG_CONFIG_HOME=str(home / "config"),
            XDG_STATE_HOME=str(home / "state"),
            TERM="xterm-256color",
            LANG="C.UTF-8",
            PYTHONPATH=str(ROOT),
        )
        if lose_below is None:
            command = [sys.executable, "-m", "rac_console"]
        else:
            command = [sys.executable, "-c", LOSING, str(lose_below)]
        width, height = size
        self.tmux(
            "new-session", "-d", "-s", "soak", "-x", str(width), "-y", str(height),
            "exec " + shlex.join(command),
        )  # fmt: skip
        self.pid = int(self.tmux("list-panes", "-t", "soak", "-F", "#{pane_pid}").strip())

    def tmux(self, *words: str) -> str:
        result = subprocess.run(
            ["tmux", "-L", self.socket, *words],
            env=self.env,
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=30,
        )
        return result.stdout

    def screen(self) -> str:
        return self.tmux("capture-pane", "-p", "-t", "soak")

    def type(self, line: str) -> None:
        self.tmux("send-keys", "-t", "soak", "-l", line)
        self.tmux("send-keys", "-t", "soak", "Enter")

    def until(self, holds: Callable[[str], bool], deadline: float) -> str | None:
        end = time.monotonic() + deadline
        while time.monotonic() < end:
            screen = self.screen()
            if holds(screen):
                return screen
            time.sleep(0.02)
        return None

    def rss_mb(self) -> float:
        try:
            status = Path(f"/proc/{self.pid}/status").read_text()
        except OSError:
            return 0.0
        found = re.search(r"VmRSS:\s+(\d+) kB", status)
        return int(found.group(1)) / 1024 if found else 0.0

    def close(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True, timeout=30)


def shown(screen: str) -> dict[str, str]:
    """What changes with the flood: the F0 and J0 values, the newest log time."""
    looks = {}
    for row in ROW.finditer(screen):
        looks[row.group(1)] = SPARKLINE.split(row.group(0).strip("│ "))[-1].strip()
    times = LOG_TIME.findall(screen)
    looks["log"] = max(times) if times else ""
    return looks


def soak(seconds: float, size: tuple[int, int], lose_below: float | None) -> Figures:
    figures = Figures()
    with tempfile.TemporaryDirectory() as home:
        console = Soak(Path(home), size, lose_below)
        try:
            if console.until(lambda s: "connected" in s, 30) is None:
                raise SystemExit("the console did not connect:\n" + console.screen())
            console.type(WATCHED)
            console.type("interval 0")
            if console.until(lambda s: "24 rows" in s and "F0" in s, 30) is None:
                raise SystemExit("the rows never showed:\n" + console.screen())
            run(console, seconds, figures)
        finally:
            console.close()
    return figures


def shows(text: str) -> Callable[[str], bool]:
    return lambda screen: text in screen


def run(console: Soak, seconds: float, figures: Figures) -> None:
    start = time.monotonic()
    last: dict[str, tuple[str, float]] = {}
    answers: list[float] = []
    rss: list[tuple[float, float]] = []
    next_key = start + KEY_EVERY
    while (now := time.monotonic()) - start < seconds:
        screen = console.screen()
        figures.reads += 1
        figures.said_behind += "BEHIND, caught up" in screen
        figures.said_engine_stopped += "ENGINE STOPPED" in screen
        for what, value in shown(screen).items():
            seen = last.get(what)
            if seen is not None:  # how long since it last changed, read now
                gap = now - seen[1]
                figures.max_gap_s[what] = round(max(figures.max_gap_s.get(what, 0.0), gap), 2)
            if seen is None or seen[0] != value:
                if seen is not None:
                    figures.changes[what] = figures.changes.get(what, 0) + 1
                last[what] = (value, now)
        if now >= next_key:
            figures.keys += 1
            answer = f"→ {1000 + figures.keys}"
            typed = time.monotonic()
            console.type(f"put I 50 {1000 + figures.keys}")
            if console.until(shows(answer), KEY_DEADLINE) is None:
                figures.keys_unanswered += 1
            else:
                answers.append(time.monotonic() - typed)
            rss.append((time.monotonic() - start, console.rss_mb()))
            next_key = time.monotonic() + KEY_EVERY
        time.sleep(max(0.0, READ_EVERY - (time.monotonic() - now)))
    figures.seconds = round(time.monotonic() - start, 1)
    if answers:
        ordered = sorted(answers)
        figures.key_median_ms = round(statistics.median(ordered) * 1000, 1)
        figures.key_p95_ms = round(ordered[int(0.95 * (len(ordered) - 1))] * 1000, 1)
        figures.key_max_ms = round(ordered[-1] * 1000, 1)
    if rss:
        after_minute = [mb for at, mb in rss if at >= 60] or [rss[-1][1]]
        figures.rss_after_first_minute_mb = round(after_minute[0], 1)
        figures.rss_end_mb = round(rss[-1][1], 1)
        figures.rss_max_mb = round(max(mb for _, mb in rss), 1)
        for minute in MEMORY_MARKS:
            marked = [mb for at, mb in rss if at >= minute * 60]
            if marked:
                figures.rss_at_minute_mb[minute] = round(marked[0], 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=3600.0)
    parser.add_argument("--lose-below", type=float, default=None)
    parser.add_argument("--size", default="120x40")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    width, height = (int(n) for n in args.size.split("x"))
    figures = soak(args.seconds, (width, height), args.lose_below)
    lost = f", one-shot timers under {args.lose_below} s lost" if args.lose_below else ""
    print(f"console soak: {figures.seconds:.0f} s at {args.size}{lost}, {figures.reads} reads")
    for what in ("F0", "J0", "log"):
        print(
            f"  {what:>3}: {figures.changes.get(what, 0)} changes, longest without one "
            f"{figures.max_gap_s.get(what, 0.0):.1f} s (target < {GAP_TARGET:g} s)"
        )
    print(
        f"  keys: {figures.keys} puts, answered median {figures.key_median_ms} ms, p95 "
        f"{figures.key_p95_ms} ms, max {figures.key_max_ms} ms, "
        f"{figures.keys_unanswered} unanswered within {KEY_DEADLINE:g} s"
    )
    growth = (
        figures.rss_end_mb / figures.rss_after_first_minute_mb - 1
        if figures.rss_after_first_minute_mb
        else 0.0
    )
    print(
        f"  memory: {figures.rss_after_first_minute_mb} MB after the first minute, "
        f"{figures.rss_end_mb} MB at the end ({growth:+.1%}), {figures.rss_max_mb} MB at most"
    )
    if figures.rss_at_minute_mb:
        marks = ", ".join(f"{mb} MB at {m} min" for m, mb in figures.rss_at_minute_mb.items())
        print(f"  memory on the way: {marks}")
    print(
        f"  the status line said the screen was behind in {figures.said_behind} reads, "
        f"the engine stopped in {figures.said_engine_stopped}"
    )
    if args.json:
        args.json.write_text(json.dumps(asdict(figures), indent=2))


if __name__ == "__main__":
    main()
