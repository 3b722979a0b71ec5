"""Key to screen in a real terminal: the console in tmux polling 200 rows flat out.

    python benchmarks/console_keys.py [--seconds 8] [--rounds 3] [--package DIR ...]
                                      [--agent] [--json FILE]

Each console (this checkout's, then each ``--package DIR``: ``PYTHONPATH=DIR``, run from
DIR) runs in its own tmux session at 120x40 (COLUMNS and LINES unset) against the C
responder (``rac-console sim`` when there is no compiler), watching ``I 0-199`` at
``interval 0``. In each round, in turn (the order turned each round), every side runs
alone while the others are stopped (SIGSTOP), so they share nothing but the machine:

  - a console: a printable character is sent to its command line every 100 ms
    (``send-keys -l``) and timed until ``capture-pane`` shows the command line holding
    it (polled every 2 ms, 2 s deadline). Both commands go through one tmux control-mode
    client, so no process is started per poll of the screen. Its poll rate is counted
    by the kernel: the bytes the console's socket received (``ss -tip``) over the same
    window, divided by the responder's 8-byte reply to ``GET ... I``; the status line's
    own "N polls/s" is shown beside it;
  - the session client: ``Session.get`` in a loop in its own process
    (``bench_clients.py session``).

With ``--agent``, this checkout's console runs a second time through an agent of its
own (``rac-console -H ... agent``), measured beside the first: its polls counted on the
agent's socket, its CPU the console's and the agent's together, both stopped while the
other sides run.

Targets: key-to-screen p95 <= 50 ms, console polls >= 0.5x the session client's rate.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shlex
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from bench_common import HERE, CPrograms, Server, child_run, proc_cpu, start_responder

KEY_EVERY = 0.1
SCREEN_POLL = 0.002
KEY_DEADLINE = 2.0
#: Typed once after each clearing of the line, so the line is found on the screen.
PREFIX = "qzqz"
ALPHABET = "xjkvbn"
#: Characters typed before the line is cleared again (Ctrl+U).
LINE_KEYS = 40
#: The C responder's reply to a GET of an I variable: "0,3,123\r".
REPLY_BYTES = 8
P95_TARGET = 50.0
RATIO_TARGET = 0.5
STATUS_RATE = re.compile(r"([\d,]+) polls/s")


class Control:
    """One tmux control-mode client (in a session of its own, so it sizes nothing):
    commands in, each answer read back between ``%begin`` and ``%end``."""

    def __init__(self, socket: str) -> None:
        self.process = subprocess.Popen(
            ["tmux", "-L", socket, "-C", "new-session", "-s", "control", "-x", "80", "-y", "24"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            bufsize=1,
        )
        # The session's own start answers first (an empty block): read up to our marker.
        self.send("display-message -p ready")
        while self.answer("display-message") != ["ready"]:
            pass

    def command(self, line: str) -> list[str]:
        self.send(line)
        return self.answer(line)

    def send(self, line: str) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(line + "\n")
        self.process.stdin.flush()

    def answer(self, line: str) -> list[str]:
        assert self.process.stdout is not None
        out: list[str] = []
        inside = False
        for text in self.process.stdout:
            text = text.rstrip("\n")
            if not inside:
                inside = text.startswith("%begin")
                continue
            if text.startswith(("%end", "%error")):
                if text.startswith("%error"):
                    raise RuntimeError(f"tmux {line!r}: {out}")
                return out
            out.append(text)
        raise RuntimeError(f"tmux control client ended during {line!r}")

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(10)


@dataclass
class Console:
    """One console under test, in tmux session ``name``."""

    label: str
    package: Path
    name: str
    pid: int = 0
    keys_ms: list[float] = field(default_factory=list)
    timeouts: int = 0
    polls: list[float] = field(default_factory=list)  # per round: polls/s (socket bytes)
    shown_rates: list[float] = field(default_factory=list)  # the status line's figure
    cpu: list[float] = field(default_factory=list)  # per round: CPU % of one core
    via_agent: bool = False  # the console attached to an agent of its own (--agent)
    agent: subprocess.Popen[str] | None = None

    @property
    def poller(self) -> int:
        """The process whose socket polls the responder: the agent's, when there is one."""
        return self.agent.pid if self.agent is not None else self.pid

    def pids(self) -> list[int]:
        return [self.pid] + ([self.agent.pid] if self.agent is not None else [])


def received_bytes(pid: int) -> int:
    """Bytes received on the process's TCP sockets, as the kernel counts them."""
    out = subprocess.run(
        ["ss", "-tinpH", "state", "established"], capture_output=True, text=True, check=True
    ).stdout
    total = 0
    mine = False
    for line in out.splitlines():
        if not line.startswith((" ", "\t")):
            mine = f"pid={pid}," in line
            continue
        if mine and (found := re.search(r"bytes_received:(\d+)", line)):
            total += int(found.group(1))
    return total


def screen(control: Control, name: str) -> list[str]:
    return control.command(f"capture-pane -p -t {name}")


def wait_for(control: Control, name: str, text: str, deadline: float = 30.0) -> list[str]:
    end = time.monotonic() + deadline
    while True:
        lines = screen(control, name)
        if any(text in line for line in lines):
            return lines
        if time.monotonic() > end:
            raise RuntimeError(f"{name}: {text!r} never shown:\n" + "\n".join(lines))
        time.sleep(0.05)


def type_line(control: Control, name: str, line: str) -> None:
    control.command(f"send-keys -t {name} -l {shlex.quote(line)}")
    control.command(f"send-keys -t {name} Enter")


def start_console(
    control: Control, socket: str, console: Console, port: int, home: Path, cell: list[int]
) -> None:
    """The console in tmux, watching 200 rows at interval 0: on one target at ``port``,
    or with ``cell`` (more ports) on a cell of them, the 200 rows shared out."""
    names = [f"127.0.0.1:{p}" for p in (port, *cell)] if cell else []
    env = {
        "HOME": home,
        "XDG_CONFIG_HOME": home,
        "XDG_STATE_HOME": home,
        "PYTHONPATH": console.package,
        "RAC_CONSOLE_AGENT_DIR": home / "agent",
    }
    if console.via_agent:
        console.agent = start_agent(console.package, port, env)
    command = (
        f"cd {shlex.quote(str(console.package))} && exec env -u COLUMNS -u LINES "
        + " ".join(f"{k}={shlex.quote(str(v))}" for k, v in env.items())
        + f" {shlex.quote(sys.executable)} -m rac_console "
        + (f"-H 127.0.0.1 -p {port}" if not cell else "-H " + ",".join(names))
        + f" --history {shlex.quote(str(home / 'history'))}"
    )
    subprocess.run(
        ["tmux", "-L", socket, "new-session", "-d", "-s", console.name, "-x", "120", "-y", "40",
         command],
        check=True,
    )  # fmt: skip
    console.pid = int(screen_value(control, console.name, "#{pane_pid}"))
    if not cell:
        wait_for(control, console.name, "type help")  # the welcome: the engine runs
        type_line(control, console.name, "watch I 0-199")
        wait_for(control, console.name, "200 rows")
        type_line(control, console.name, "interval 0")
        wait_for(control, console.name, "polls/s")
    else:
        wait_for(control, console.name, "Next target")  # the cell's console runs
        share = 200 // len(names)
        for name in names:
            type_line(control, console.name, f"@{name} watch I 0-{share - 1}")
        wait_for(control, console.name, f"{share * len(names)} rows")
        for name in names:
            type_line(control, console.name, f"@{name} interval 0")
    if console.via_agent:
        wait_for(control, console.name, "via agent")
    before = received_bytes(console.poller)
    time.sleep(1.0)
    if received_bytes(console.poller) <= before:
        raise RuntimeError(f"{console.label}: the console is not polling")


def start_agent(package: Path, port: int, env: dict[str, object]) -> subprocess.Popen[str]:
    """``rac-console -H 127.0.0.1 -p PORT agent`` for one console; once it listens."""
    agent = subprocess.Popen(
        [sys.executable, "-m", "rac_console", "-H", "127.0.0.1", "-p", str(port), "agent"],
        cwd=package,
        env={**os.environ, **{k: str(v) for k, v in env.items()}},
        stdout=subprocess.PIPE,
        text=True,
    )
    assert agent.stdout is not None
    for line in agent.stdout:
        if "listening on" in line:
            return agent
    raise RuntimeError("the agent did not start")


def screen_value(control: Control, name: str, fmt: str) -> str:
    return control.command(f"display-message -p -t {name} {shlex.quote(fmt)}")[0]


def clear_line(control: Control, console: Console) -> str:
    """Empty the command line, type PREFIX and wait until it shows: the line so far."""
    control.command(f"send-keys -t {console.name} C-u")
    end = time.monotonic() + 5
    while any(PREFIX in line for line in screen(control, console.name)):
        if time.monotonic() > end:
            raise RuntimeError(f"{console.label}: Ctrl+U did not clear the command line")
        time.sleep(0.01)
    control.command(f"send-keys -t {console.name} -l {PREFIX}")
    wait_for(control, console.name, PREFIX, 5)
    return PREFIX


def measure_console(control: Control, console: Console, seconds: float) -> None:
    """One round: keys timed for ``seconds`` while the console polls; its poll rate
    (with an agent: the agent's socket, and the CPU of both)."""
    for pid in console.pids():
        os.kill(pid, signal.SIGCONT)
    time.sleep(1.0)  # polling back at speed
    typed = clear_line(control, console)
    cpu0 = sum(proc_cpu(pid) for pid in console.pids())
    bytes0, t0 = received_bytes(console.poller), time.monotonic()
    lines: list[str] = []
    next_key = time.monotonic() + KEY_EVERY
    n = 0
    while time.monotonic() - t0 < seconds:
        if len(typed) >= len(PREFIX) + LINE_KEYS:
            typed = clear_line(control, console)
        time.sleep(max(0.0, next_key - time.monotonic()))
        next_key = time.monotonic() + KEY_EVERY
        char = ALPHABET[n % len(ALPHABET)]
        n += 1
        typed += char
        sent = time.perf_counter()
        control.command(f"send-keys -t {console.name} -l {char}")
        while True:
            lines = screen(control, console.name)
            elapsed = time.perf_counter() - sent
            if any(typed in line for line in lines):
                console.keys_ms.append(elapsed * 1000)
                break
            if elapsed > KEY_DEADLINE:
                console.keys_ms.append(elapsed * 1000)
                console.timeouts += 1
                typed = clear_line(control, console)  # start again from a known line
                break
            time.sleep(SCREEN_POLL)
    t1 = time.monotonic()
    polls = (received_bytes(console.poller) - bytes0) / REPLY_BYTES
    cpu1 = sum(proc_cpu(pid) for pid in console.pids())
    console.cpu.append((cpu1 - cpu0) / (t1 - t0) * 100)
    console.polls.append(polls / (t1 - t0))
    shown = [m.group(1) for line in lines if (m := STATUS_RATE.search(line))]
    if shown:
        console.shown_rates.append(float(shown[0].replace(",", "")))
    control.command(f"send-keys -t {console.name} C-u")
    for pid in console.pids():
        os.kill(pid, signal.SIGSTOP)


class SimServer(Server):
    """``rac-console sim --port 0``: the port read from its first line."""

    def __init__(self) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "rac_console", "sim", "--port", "0"],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.process.stdout is not None
        self.port = int(self.process.stdout.readline().split(":")[-1].split()[0])
        self.pid = self.process.pid


def percentile(values: list[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[max(0, int(len(ordered) * fraction + 0.5) - 1)]


def loadavg() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "?"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=8.0, help="key window per round")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument(
        "--package",
        action="append",
        default=[],
        metavar="DIR",
        help="another checkout's console, measured beside this one's (repeatable)",
    )
    parser.add_argument("--json", metavar="FILE")
    parser.add_argument(
        "--agent",
        action="store_true",
        help="this checkout's console also through an agent of its own, beside it",
    )
    parser.add_argument(
        "--cell",
        type=int,
        default=1,
        metavar="N",
        help="the console on a cell of N targets (a C responder each), the 200 rows shared",
    )
    args = parser.parse_args()

    socket = f"rac-keys-{os.getpid()}"
    packages = [("this", HERE.parent)] + [(Path(p).name, Path(p).resolve()) for p in args.package]
    consoles = [
        Console(label, package, f"console{n}") for n, (label, package) in enumerate(packages)
    ]
    if args.agent:
        consoles.append(Console("agent", HERE.parent, "console-agent", via_agent=True))
    load_before = loadavg()
    programs = CPrograms()
    server: Server | None = None
    more: list[Server] = []
    control: Control | None = None
    session_rates: list[float] = []
    session_cpu: list[float] = []
    with tempfile.TemporaryDirectory(prefix="rac-keys-") as tmp:
        try:
            if programs.responder is not None:
                server, what = start_responder(programs)
            else:
                server, what = SimServer(), "rac-console sim (no C compiler)"
            port = server.port
            more = [start_responder(programs)[0] for _ in range(args.cell - 1)]
            cell = [extra.port for extra in more]
            print(f"against the {what} on 127.0.0.1:{port}; load {load_before}", flush=True)
            if cell:
                print(f"a cell of {args.cell} targets, the 200 rows shared", flush=True)
            control = Control(socket)
            for console in consoles:
                home = Path(tmp) / console.name
                home.mkdir()
                start_console(control, socket, console, port, home, cell)
                for pid in console.pids():
                    os.kill(pid, signal.SIGSTOP)
            sides: list[Console | None] = [None, *consoles]  # None: the session client
            for n in range(args.rounds):
                order = sides if n % 2 == 0 else sides[::-1]
                for side in order:
                    if side is None:
                        run = child_run("bench_clients.py", "session", port, args.seconds)
                        session_rates.append(run.rate)
                        session_cpu.append(run.cpu / run.seconds * 100)
                    else:
                        measure_console(control, side, args.seconds)
                print(f"round {n + 1}/{args.rounds} done; load {loadavg()}", flush=True)
        finally:
            for console in consoles:
                for pid in console.pids() if console.pid else ():
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(pid, signal.SIGCONT)
            subprocess.run(["tmux", "-L", socket, "kill-server"], capture_output=True, check=False)
            if control is not None:
                control.close()
            for console in consoles:
                if console.pid:
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(console.pid, signal.SIGKILL)  # gone with its terminal, or now
            for console in consoles:
                if console.agent is not None:
                    console.agent.terminate()
                    console.agent.wait(10)
            if server is not None:
                server.stop()
            for extra in more:
                extra.stop()
            programs.cleanup()

    session = statistics.median(session_rates)
    results: dict[str, object] = {
        "load_before": load_before,
        "load_after": loadavg(),
        "session_gets_per_s": session,
        "session_cpu_percent": statistics.median(session_cpu),
    }
    print()
    print(f"session client (Session.get loop): {session:,.0f} GETs/s, "
          f"{statistics.median(session_cpu):.0f}% CPU")  # fmt: skip
    header = (f"{'console':<10} {'keys':>5} {'median ms':>9} {'p95 ms':>7} {'max ms':>7} "
              f"{'late':>4} {'polls/s':>9} {'status':>9} {'x session':>9} {'CPU %':>6}"
              "  targets")  # fmt: skip
    print(header)
    for console in consoles:
        keys = console.keys_ms
        median, p95 = statistics.median(keys), percentile(keys, 0.95)
        polls = statistics.median(console.polls)
        ratio = polls / session
        shown = statistics.median(console.shown_rates) if console.shown_rates else float("nan")
        met = p95 <= P95_TARGET and ratio >= RATIO_TARGET
        verdict = (
            f"p95<={P95_TARGET:.0f} {'yes' if p95 <= P95_TARGET else 'NO'}, "
            f"x>={RATIO_TARGET} {'yes' if ratio >= RATIO_TARGET else 'NO'}"
        )
        print(f"{console.label:<10} {len(keys):>5} {median:>9.1f} {p95:>7.1f} {max(keys):>7.1f} "
              f"{console.timeouts:>4} {polls:>9,.0f} {shown:>9,.0f} {ratio:>9.2f} "
              f"{statistics.median(console.cpu):>6.0f}  {verdict}")  # fmt: skip
        results[console.label] = {
            "package": str(console.package),
            "key_median_ms": median,
            "key_p95_ms": p95,
            "key_max_ms": max(keys),
            "keys": len(keys),
            "key_timeouts": console.timeouts,
            "polls_per_s": polls,
            "status_line_polls_per_s": shown,
            "to_session_ratio": ratio,
            "cpu_percent": statistics.median(console.cpu),
            "targets_met": met,
        }
    print(f"load before {load_before}, after {results['load_after']}")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
