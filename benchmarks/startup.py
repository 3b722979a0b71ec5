"""Start-up: how long a user waits for ``--version``, a one-shot ``get`` and the console.

    python benchmarks/startup.py [--runs 15] [--package DIR]

Each figure is the median and quartiles of ``--runs`` interleaved rounds (the order of
the sides reversed every other round), every side a fresh process:

- ``python -m rac_console --version``;
- ``python -m rac_console -H 127.0.0.1 -p PORT get I 1`` against a simulator process
  started once for the whole run, and, from one more run under a ``-c`` wrapper that
  calls ``main``, how many modules it loaded and which of asyncio, ssl, the simulator
  and Textual;
- the console's first paint (``python -m rac_console`` in a real 120x40 pty, until the
  screen names its target: ``SIMULATOR``, as ``benchmarks/run.py`` measures it) beside
  a minimal Textual app's (one ``Static``, until its text shows), in the same rounds.

``--package DIR`` times another checkout's package too (DIR first on PYTHONPATH, run
from DIR), in the same rounds, as a column of its own. Byte code goes to a cache
directory of this run's (PYTHONPYCACHEPREFIX), compiled by one untimed round, so no
checkout is written to and none recompiles on every start.
"""

from __future__ import annotations

import argparse
import json
import os
import pty
import select
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

THIS_CHECKOUT = Path(__file__).resolve().parent.parent

#: What must not be loaded by a one-shot command when a host is given.
HEAVY = ("asyncio", "ssl", "rac_console.sim", "textual")

#: A Textual app that composes one Static: the floor the console's first paint is held to.
MINIMAL_APP = """
from textual.app import App, ComposeResult
from textual.widgets import Static


class Minimal(App[None]):
    def compose(self) -> ComposeResult:
        yield Static("MINIMAL-READY")


Minimal().run()
"""

#: Runs ``main`` as the command line would, then says what it loaded (after a marker).
MODULES_PROBE = """
import sys
from rac_console.cli.main import main
import rac_console
status = main(sys.argv[1:])
heavy = [m for m in {heavy!r} if m in sys.modules]
print("PROBE", status, len(sys.modules), ",".join(heavy) or "none", rac_console.__file__)
"""

VERSION_TARGET_MS = 60
GET_TARGET_MS = 120
PAINT_RATIO_TARGET = 1.3


@dataclass
class Package:
    """A checkout whose ``rac_console`` is timed: its root, and the environment and
    working directory its processes get."""

    label: str
    root: Path
    env: dict[str, str]
    times: dict[str, list[float]] = field(default_factory=dict)
    ratios: list[float] = field(default_factory=list)  # first paint / minimal app's, per round
    probe: str = ""

    def add(self, name: str, seconds: float) -> None:
        self.times.setdefault(name, []).append(seconds)


def environment(root: Path | None, cache: Path) -> dict[str, str]:
    """The child's environment: byte code cached (never PYTHONDONTWRITEBYTECODE, which
    recompiles an editable install on every start), ``root`` first on the path."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(cache)
    if root is not None:
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (str(root), os.environ.get("PYTHONPATH", "")) if p
        )
    return env


def timed_run(command: list[str], env: dict[str, str], cwd: Path) -> float:
    """Process start to exit, output captured; a failing command stops the run."""
    started = time.perf_counter()
    result = subprocess.run(command, env=env, cwd=cwd, capture_output=True, check=False)
    elapsed = time.perf_counter() - started
    if result.returncode != 0:
        raise SystemExit(f"{command} failed ({result.returncode}): {result.stderr.decode()}")
    return elapsed


def first_paint(command: list[str], marker: bytes, env: dict[str, str], cwd: Path) -> float:
    """Process start to the first screen output holding ``marker``, in a real pty."""
    with tempfile.TemporaryDirectory() as home:
        env = env | {
            "HOME": home,
            "XDG_STATE_HOME": home,
            "XDG_CONFIG_HOME": home,
            "TERM": "xterm-256color",
            "COLUMNS": "120",
            "LINES": "40",
        }
        master, slave = pty.openpty()
        started = time.perf_counter()
        process = subprocess.Popen(
            command, stdin=slave, stdout=slave, stderr=slave, env=env, cwd=cwd, close_fds=True
        )
        os.close(slave)
        seen, painted = b"", None
        try:
            while painted is None and time.perf_counter() - started < 20:
                ready, _, _ = select.select([master], [], [], 0.5)
                if not ready:
                    continue
                try:
                    seen += os.read(master, 65536)
                except OSError:
                    break
                if marker in seen:
                    painted = time.perf_counter() - started
        finally:
            process.terminate()
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=10)
            os.close(master)
    if painted is None:
        raise SystemExit(f"{command} never showed {marker!r}; it showed {seen[-400:]!r}")
    return painted


def start_simulator(env: dict[str, str]) -> tuple[subprocess.Popen[str], int]:
    """``rac-console sim --port 0`` of this checkout: the process and its port."""
    process = subprocess.Popen(
        [sys.executable, "-m", "rac_console", "sim", "--port", "0"],
        env=env,
        cwd=THIS_CHECKOUT,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    assert process.stdout is not None
    line = process.stdout.readline()  # "RC8 simulator listening on 127.0.0.1:PORT (...)"
    try:
        port = int(line.split("127.0.0.1:")[1].split()[0])
    except (IndexError, ValueError):
        process.kill()
        raise SystemExit(f"the simulator did not say its port: {line!r}") from None
    return process, port


def probe_modules(package: Package, get_words: list[str]) -> str:
    """One ``get`` under the wrapper: status, modules loaded, heavy ones, package file."""
    result = subprocess.run(
        [sys.executable, "-c", MODULES_PROBE.format(heavy=HEAVY), *get_words],
        env=package.env,
        cwd=package.root,
        capture_output=True,
        text=True,
        check=False,
    )
    lines = [line for line in result.stdout.splitlines() if line.startswith("PROBE ")]
    if not lines:
        raise SystemExit(f"the module probe failed: {result.stderr}")
    return lines[-1]


def spread(values: list[float], scale: float = 1000.0) -> str:
    """Median [first quartile-third quartile], in ms by default."""
    if len(values) < 2:
        return f"{values[0] * scale:.0f}" if values else "-"
    q1, median, q3 = statistics.quantiles(values, n=4, method="inclusive")
    digits = 0 if scale == 1000.0 else 2
    return f"{median * scale:.{digits}f} [{q1 * scale:.{digits}f}-{q3 * scale:.{digits}f}]"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=15, help="interleaved rounds (15)")
    parser.add_argument(
        "--package", type=Path, help="another checkout to time beside this one (read only)"
    )
    parser.add_argument("--json", type=Path, help="write the medians here too")
    options = parser.parse_args()

    with tempfile.TemporaryDirectory() as scratch:
        cache = Path(scratch) / "pycache"
        packages = []
        if options.package is not None:
            root = options.package.resolve()
            packages.append(Package(str(root), root, environment(root, cache)))
        packages.append(Package("this checkout", THIS_CHECKOUT, environment(THIS_CHECKOUT, cache)))
        plain_env = environment(None, cache)
        simulator, port = start_simulator(packages[-1].env)
        get_words = ["-H", "127.0.0.1", "-p", str(port), "get", "I", "1"]
        module = [sys.executable, "-m", "rac_console"]
        try:
            for package in packages:
                package.probe = probe_modules(package, get_words)
            sides: list[tuple[str, Package | None, Callable[[], float]]] = []
            for package in packages:
                env, cwd = package.env, package.root
                sides += [
                    ("version", package, partial(timed_run, [*module, "--version"], env, cwd)),
                    ("get", package, partial(timed_run, [*module, *get_words], env, cwd)),
                    ("paint", package, partial(first_paint, module, b"SIMULATOR", env, cwd)),
                ]
            minimal_app = [sys.executable, "-c", MINIMAL_APP]
            sides.append(
                (
                    "minimal",
                    None,
                    partial(first_paint, minimal_app, b"MINIMAL-READY", plain_env, THIS_CHECKOUT),
                )
            )
            for _, _, run in sides:  # untimed: compiles the byte code into the cache
                run()
            minimal: list[float] = []
            for round_number in range(options.runs):
                order = sides if round_number % 2 == 0 else sides[::-1]
                paints: dict[str, float] = {}
                for name, package, run in order:
                    seconds = run()
                    if package is None:
                        minimal.append(seconds)
                    else:
                        package.add(name, seconds)
                        if name == "paint":
                            paints[package.label] = seconds
                for package in packages:
                    package.ratios.append(paints[package.label] / minimal[-1])
                print(f"round {round_number + 1}/{options.runs}", file=sys.stderr)
        finally:
            simulator.terminate()
            simulator.wait(timeout=10)
    report(packages, minimal, options.runs)
    if options.json is not None:
        figures: dict[str, object] = {}
        for package in packages:
            key = "old" if package.root != THIS_CHECKOUT else "new"
            for name, values in package.times.items():
                figures[f"{key}.{name}_ms"] = statistics.median(values) * 1000
            figures[f"{key}.paint_ratio"] = statistics.median(package.ratios)
            figures[f"{key}.get_imports"] = package.probe.split(" ", 4)[3]
        figures["minimal_paint_ms"] = statistics.median(minimal) * 1000
        options.json.write_text(json.dumps(figures, indent=2) + "\n", encoding="utf-8")
    return 0


def report(packages: list[Package], minimal: list[float], runs: int) -> None:
    """The table: one column per package, then the target and whether each met it."""
    width = 30
    python = sys.version.split()[0]
    print(f"start-up, {runs} interleaved rounds: median [quartiles], ms; python {python}")
    header = f"{'':38}" + "".join(f"{p.label[-width:]:>{width}}" for p in packages)
    print(header + f"  {'target':>12}  met")

    def row(label: str, cells: list[str], target: str = "", met: list[bool] | None = None) -> None:
        verdict = " / ".join("yes" if m else "NO" for m in met) if met is not None else ""
        print(
            f"{label:38}" + "".join(f"{c:>{width}}" for c in cells) + f"  {target:>12}  {verdict}"
        )

    def median(values: list[float]) -> float:
        return statistics.median(values)

    probes = [p.probe.split(" ", 4) for p in packages]  # PROBE status count heavy file
    row(
        "--version",
        [spread(p.times["version"]) for p in packages],
        f"<= {VERSION_TARGET_MS} ms",
        [median(p.times["version"]) * 1000 <= VERSION_TARGET_MS for p in packages],
    )
    row(
        "get I 1 (simulator process)",
        [spread(p.times["get"]) for p in packages],
        f"<= {GET_TARGET_MS} ms",
        [median(p.times["get"]) * 1000 <= GET_TARGET_MS for p in packages],
    )
    row("  modules loaded by get", [probe[2] for probe in probes])
    row(
        "  asyncio/ssl/sim/textual loaded",
        [probe[3] for probe in probes],
        "none",
        [probe[3] == "none" for probe in probes],
    )
    row("console first paint", [spread(p.times["paint"]) for p in packages])
    row("minimal Textual app first paint", [spread(minimal) for _ in packages])
    row(
        "console / minimal app (per round)",
        [spread(p.ratios, scale=1.0) for p in packages],
        f"<= {PAINT_RATIO_TARGET}x",
        [median(p.ratios) <= PAINT_RATIO_TARGET for p in packages],
    )
    for package, probe in zip(packages, probes, strict=True):
        print(f"{package.label}: rac_console from {Path(probe[4]).parent}")


if __name__ == "__main__":
    raise SystemExit(main())
