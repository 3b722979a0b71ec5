"""Pulled cables: what the console, the REPL and ``watch`` show over a real network path.

    python benchmarks/network_paths.py [--quick] [--deadline S] [--hold S] [--verbose]

Loopback never loses a packet, so the failures that matter at a cell (a cable pulled, a
controller rebooted behind a dead connection, a PUT whose reply never comes) are tried
here over a veth pair between two network namespaces (root, ``ip`` and ``iptables``):

  - ``racA-PID`` holds the controller: ``rac-console sim --bind 10.77.0.2 --port 5006``;
  - ``racB-PID`` holds the clients, from 10.77.0.1: the console and the REPL, each in a
    tmux server of its own started inside B (read with ``capture-pane``), and
    ``rac-console watch I 10-19 --every 0.2 --json`` read line by line.

The cable is pulled on A's side: ``iptables -A INPUT -i VETH -j DROP`` and ``-A OUTPUT
-o VETH -j DROP`` in A (only the veth, so A can still reach its simulator over loopback
to preset and read values while the cable is out); ``iptables -F`` in A restores it.
The PUT cases also pull it the moment a PUT arrives (``-m string`` and ``-m recent``):
just after it (the write lands, its reply is lost) or just before (the request is lost).

Every watched variable I k (k = 10..19; I0 moves by itself and is read-only) holds
1000 + k, so a reply taken for another request shows: each case counts values shown for
I k that are not 1000 + k (wrong attributions) and PUT reports that disagree with what
the controller holds afterwards (wrong write reports); both must be 0.

Where namespaces cannot be made it prints ``network paths: skipped: WHY`` and exits 0.
It asserts nothing; ``tests/test_network_paths.py`` checks the final line.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import queue
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

SIM_HOST, CLIENT_HOST, PORT = "10.77.0.2", "10.77.0.1", 5006
WATCHED = range(10, 20)
PUT_INDEX, PUT_VALUE = 50, 7777
RAC = (sys.executable, "-m", "rac_console")
SAMPLE_EVERY = 0.1
SETTLE_AFTER_PUT = 5.0  # a PUT held up on the network has this long to land late


def expected(index: int) -> int:
    """What I ``index`` holds all along: a value that names its variable."""
    return 1000 + index


def run(
    cmd: list[str],
    timeout: float = 30,
    input: str | None = None,
    env: dict[str, str] | None = None,
    cwd: Path | None = None,
) -> subprocess.CompletedProcess[str]:
    """A command that must succeed, its output kept for the message when it does not."""
    return subprocess.run(
        cmd,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=True,
        input=input,
        env=env,
        cwd=cwd,
    )


def failure(exc: BaseException) -> str:
    """One line saying why a command failed."""
    if isinstance(exc, subprocess.CalledProcessError):
        said = (exc.stderr or exc.stdout or "").strip().splitlines()
        return f"{shlex.join(exc.cmd)}: {said[-1] if said else f'exit {exc.returncode}'}"
    return str(exc) or type(exc).__name__


# ----------------------------------------------------------------------- network


class Net:
    """Namespaces A (controller) and B (clients) joined by a veth pair; A's firewall
    is the cable."""

    def __init__(self, tag: str) -> None:
        self.a, self.b = f"racA-{tag}", f"racB-{tag}"
        self.veth_a, self.veth_b = f"rnA{tag}"[:15], f"rnB{tag}"[:15]
        self._made: list[str] = []
        self._veth = False

    def up(self) -> None:
        for name in (self.a, self.b):
            run(["ip", "netns", "add", name])
            self._made.append(name)
        run(["ip", "link", "add", self.veth_a, "type", "veth", "peer", "name", self.veth_b])
        self._veth = True
        for side, veth, address in (
            (self.a, self.veth_a, SIM_HOST),
            (self.b, self.veth_b, CLIENT_HOST),
        ):
            run(["ip", "link", "set", veth, "netns", side])
            run(["ip", "-n", side, "addr", "add", f"{address}/24", "dev", veth])
            run(["ip", "-n", side, "link", "set", veth, "up"])
            run(["ip", "-n", side, "link", "set", "lo", "up"])
        run(self.in_a("iptables", "-S"))  # the firewall answers in a namespace

    def in_a(self, *cmd: str) -> list[str]:
        return ["ip", "netns", "exec", self.a, *cmd]

    def in_b(self, *cmd: str) -> list[str]:
        return ["ip", "netns", "exec", self.b, *cmd]

    def pull(self) -> None:
        """The cable out: nothing crosses A's veth either way."""
        run(self.in_a("iptables", "-A", "INPUT", "-i", self.veth_a, "-j", "DROP"))
        run(self.in_a("iptables", "-A", "OUTPUT", "-o", self.veth_a, "-j", "DROP"))

    def pull_at_put(self, before: bool) -> None:
        """The cable out the moment a PUT arrives: with ``before`` its packet is dropped
        too (the request is lost); without, it reaches the simulator and only what
        follows is lost (the write lands, its reply never comes)."""
        seen = ["-m", "recent", "--name", f"put{os.getpid()}"]
        inward, outward = ["INPUT", "-i", self.veth_a], ["OUTPUT", "-o", self.veth_a]
        put = ["-m", "string", "--string", "PUT:RC8:", "--algo", "bm"]
        for rule in (
            [*inward, *seen, "--rcheck", "--rsource", "-j", "DROP"],  # once seen, nothing in
            [*inward, *put, *seen, "--set", "--rsource", *(["-j", "DROP"] if before else [])],
            [*outward, *seen, "--rcheck", "--rdest", "-j", "DROP"],  # nor out
        ):
            run(self.in_a("iptables", "-A", *rule))

    def can_pull_at_put(self) -> str | None:
        """Why the string and recent matches cannot be used here; None when they can."""
        try:
            self.pull_at_put(before=True)
        except (subprocess.SubprocessError, OSError) as exc:
            return failure(exc)
        finally:
            self.restore()
        return None

    def restore(self) -> None:
        run(self.in_a("iptables", "-F"))

    def down(self) -> None:
        """Everything made, gone: our processes left in the namespaces first (they keep
        a namespace alive), then the namespaces (the veth pair goes with them)."""
        for name in self._made:
            with contextlib.suppress(subprocess.SubprocessError, OSError):
                pids = run(["ip", "netns", "pids", name], timeout=10).stdout.split()
                for pid in pids:
                    with contextlib.suppress(OSError, ValueError):
                        os.kill(int(pid), signal.SIGKILL)
        for name in reversed(self._made):
            with contextlib.suppress(subprocess.SubprocessError, OSError):
                run(["ip", "netns", "del", name], timeout=10)
        if self._veth:  # still in this namespace when setting up failed half-way
            subprocess.run(["ip", "link", "del", self.veth_a], capture_output=True, timeout=10)
        self._made.clear()
        self._veth = False


def why_not() -> str | None:
    """Why namespaces cannot be made here (None when they can be)."""
    if sys.platform != "linux":
        return "network namespaces are Linux only"
    if os.geteuid() != 0:
        return "not root (ip netns and iptables need it)"
    for tool in ("ip", "iptables", "tmux"):
        if shutil.which(tool) is None:
            return f"no {tool} on PATH"
    return None


# -------------------------------------------------------------------- controller


class Controller:
    """The simulator in namespace A, at 10.77.0.2:5006 as a controller on the cell network."""

    def __init__(self, net: Net, scratch: Path, env: dict[str, str]) -> None:
        self.net, self.scratch, self.env = net, scratch, env
        self.process: subprocess.Popen[str] | None = None
        self.starts = 0

    def start(self, deadline: float = 20) -> None:
        self.starts += 1
        err = open(self.scratch / f"sim-{self.starts}.err", "w")  # noqa: SIM115
        self.process = subprocess.Popen(
            self.net.in_a(*RAC, "sim", "--bind", SIM_HOST, "--port", str(PORT)),
            stdout=subprocess.PIPE,
            stderr=err,
            text=True,
            cwd=self.scratch,
            env=self.env,
        )
        err.close()
        lines: queue.Queue[str] = queue.Queue()
        stdout = self.process.stdout
        assert stdout is not None
        threading.Thread(target=lambda: lines.put(stdout.readline()), daemon=True).start()
        try:
            first = lines.get(timeout=deadline)
        except queue.Empty:
            first = ""
        if "listening on" not in first:
            raise RuntimeError(f"the simulator did not start in namespace A: {first!r}")

    def kill(self) -> None:
        """Power off: SIGKILL, no goodbye on any connection."""
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
        if self.process is not None:
            self.process.wait(10)
            if self.process.stdout is not None:
                self.process.stdout.close()

    def preset(self) -> None:
        """I k = 1000 + k, over A's loopback (works with the cable out)."""
        self.put_values({k: expected(k) for k in (*WATCHED, PUT_INDEX)})

    def put_values(self, values: dict[int, int]) -> None:
        script = "".join(f"put I {k} {v}\n" for k, v in values.items())
        done = run(
            self.net.in_a(*RAC, "-H", SIM_HOST, "--json", "run", "-"),
            input=script,
            env=self.env,
            cwd=self.scratch,
        )
        reports = [json.loads(line) for line in done.stdout.splitlines() if line.strip()]
        if len(reports) != len(values) or not all(r.get("verified") for r in reports):
            raise RuntimeError(f"presetting the simulator failed: {done.stdout[-500:]}")

    def read(self, index: int) -> int | None:
        """What the controller holds now, asked over A's loopback."""
        try:
            done = run(
                self.net.in_a(*RAC, "-H", SIM_HOST, "--json", "get", "I", str(index)),
                env=self.env,
                cwd=self.scratch,
            )
            value = json.loads(done.stdout.strip().splitlines()[-1]).get("value")
        except (subprocess.SubprocessError, OSError, ValueError, IndexError):
            return None
        return value if isinstance(value, int) else None


# ----------------------------------------------------------------------- clients


@dataclass
class View:
    """What one client showed at one look."""

    rows: dict[int, tuple[str, int | None]] = field(default_factory=dict)  # I k: status, value
    state: str | None = None  # the console's connection state
    text: str = ""
    lines: list[dict[str, Any]] = field(
        default_factory=list
    )  # watch: JSON lines since the last look


class Attribution:
    """Values shown for I k that are not 1000 + k: a reply taken for another request.
    On a screen a wrong value counts when it appears, not at every look."""

    def __init__(self) -> None:
        self.case = ""
        self.wrong: Counter[tuple[str, str]] = Counter()
        self.examples: list[str] = []
        self._last: dict[tuple[str, int], int] = {}

    def see(self, client: str, index: int, value: int | None, every: bool = False) -> None:
        if value is None or index not in WATCHED:
            return
        if not every and self._last.get((client, index)) == value:
            return
        self._last[(client, index)] = value
        if value != expected(index):
            self.wrong[(self.case, client)] += 1
            self.examples.append(f"{self.case}: {client} showed I{index} = {value}")


#: How the console's status line may begin its connection state (a field between ``·``).
STATES = ("connected", "connecting", "lost", "dropped", "disconnected", "idle")
STATUS = r"(OK|[A-Z_]+(?: [A-Z_]+)*(?: \(stale\))?)"
CONSOLE_ROW = re.compile(r"^│ I(\d+)\s+" + STATUS + r"\s")
CONSOLE_VALUE = re.compile(r"\s(-?\d+)\s+VT_\w+")
REPL_ROW = re.compile(r"^I(\d+)\s+" + STATUS + r"\s+\S+(?:\s+(-?\d+))?\s*$")


class Pane:
    """A client in a tmux server of its own, started inside namespace B."""

    ECHO = "› "  # what precedes a line typed, once it ran

    def __init__(
        self,
        net: Net,
        name: str,
        argv: list[str],
        env: dict[str, str],
        cwd: Path,
        attribution: Attribution,
    ) -> None:
        self.net, self.name, self.argv, self.env, self.cwd = net, name, argv, env, cwd
        self.socket = f"racnet-{os.getpid()}-{name}"
        self.attribution = attribution

    def tmux(self, *args: str) -> list[str]:
        return ["tmux", "-L", self.socket, *args]

    def start(self) -> None:
        new = ["new-session", "-d", "-s", self.name, "-x", "120", "-y", "40", "-c", str(self.cwd)]
        run(self.net.in_b(*self.tmux(*new, shlex.join(self.argv))), env=self.env)
        run(self.tmux("set-option", "-t", self.name, "remain-on-exit", "on"))

    def screen(self) -> str:
        try:
            return run(self.tmux("capture-pane", "-p", "-t", self.name), timeout=10).stdout
        except (subprocess.SubprocessError, OSError):
            return ""

    def type(self, line: str) -> None:
        run(self.tmux("send-keys", "-t", self.name, "-l", line))
        run(self.tmux("send-keys", "-t", self.name, "Enter"))

    def type_keys(self, *keys: str) -> None:
        run(self.tmux("send-keys", "-t", self.name, *keys))

    def stop(self) -> None:
        """The server and its socket file (tmux leaves it behind)."""
        subprocess.run(self.tmux("kill-server"), capture_output=True, timeout=10)
        folder = Path(os.environ.get("TMUX_TMPDIR") or "/tmp") / f"tmux-{os.getuid()}"
        (folder / self.socket).unlink(missing_ok=True)

    def result_of(self, typed: str) -> str | None:
        """The first line printed after the last echo of ``typed``; None before any."""
        lines = self.screen().splitlines()
        echo = self.ECHO + typed
        marks = [n for n, line in enumerate(lines) if line.rstrip().endswith(echo)]
        if not marks or marks[-1] + 1 >= len(lines):
            return None
        return lines[marks[-1] + 1].strip() or None  # the result comes on the next line


class ConsoleView(Pane):
    def settled_screen(self) -> tuple[str, bool]:
        """The screen, and whether it was whole: two captures in a row alike. A capture
        taken while the console redraws a line can hold half of the old line and half of
        the new (tmux's capture-pane does not wait for the end of a synchronized update):
        a busy machine once showed I10 to I13 as 1, the first digit of each value."""
        text = self.screen()
        for _ in range(5):
            again = self.screen()
            if again == text:
                return text, True
            text = again
        return text, False

    def look(self) -> View:
        text, whole = self.settled_screen()
        view = View(text=text)
        lines = text.splitlines()
        fields = [part.strip() for part in lines[0].split(" · ")] if lines else []
        view.state = next((f for f in fields if f.startswith(STATES)), None)
        for line in lines:
            row = CONSOLE_ROW.match(line)
            if row:
                value = CONSOLE_VALUE.search(line[row.end() :])
                number = int(value.group(1)) if value else None
                view.rows[int(row.group(1))] = (row.group(2), number)
                if whole:  # a torn capture is no value shown
                    self.attribution.see("console", int(row.group(1)), number)
        return view


class ReplView(Pane):
    ECHO = "> "  # the prompt

    def look(self) -> View:
        text = self.screen()
        view = View(text=text)
        lines = text.splitlines()
        heads = [n for n, line in enumerate(lines) if line.startswith("Variable  Label")]
        for line in lines[heads[-1] + 1 :] if heads else []:
            row = REPL_ROW.match(line)
            if not row:
                break
            number = int(row.group(3)) if row.group(3) else None
            view.rows[int(row.group(1))] = (row.group(2), number)
            self.attribution.see("REPL", int(row.group(1)), number)
        return view


class WatchStream:
    """``rac-console watch I 10-19 --every 0.2 --json`` in namespace B, read line by line
    (each line timed as it arrives)."""

    def __init__(self, net: Net, env: dict[str, str], cwd: Path, attribution: Attribution) -> None:
        first, last = WATCHED[0], WATCHED[-1]
        self.process = subprocess.Popen(
            net.in_b(
                *RAC, "-H", SIM_HOST, "--json", "watch", "I", f"{first}-{last}", "--every", "0.2"
            ),
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            env=env,
            cwd=cwd,
        )
        self.attribution = attribution
        self._lines: queue.Queue[dict[str, Any]] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            with contextlib.suppress(ValueError):
                self._lines.put(json.loads(line))

    def look(self) -> View:
        view = View()
        while True:
            try:
                line = self._lines.get_nowait()
            except queue.Empty:
                break
            view.lines.append(line)
            for name, value in (line.get("values") or {}).items():
                if name.startswith("I") and name[1:].isdigit() and isinstance(value, int):
                    self.attribution.see("watch", int(name[1:]), value, every=True)
        return view

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(5)
        if self.process.stdout is not None:
            self.process.stdout.close()


# ------------------------------------------------------------------ conditions

Check = Callable[[View], str | None]
Checks = dict[str, tuple[ConsoleView | ReplView | WatchStream, Check]]


def rows_not_ok(view: View) -> str | None:
    bad = [(k, status) for k, (status, _) in sorted(view.rows.items()) if status != "OK"]
    return f"I{bad[0][0]} {bad[0][1]}" if bad else None


def rows_all_ok(view: View) -> str | None:
    fresh = [k for k, (status, value) in view.rows.items() if status == "OK" and value is not None]
    return f"{len(fresh)} rows OK" if len(fresh) == len(WATCHED) else None


def state_not_connected(view: View) -> str | None:
    return view.state if view.state not in (None, "connected") else None


def state_connected(view: View) -> str | None:
    return "connected" if view.state == "connected" else None


def gaps_in_log(before: View, now: View) -> list[str]:
    """The console frame log's ``── … ──`` marks on screen ``now`` but not ``before``."""
    old = set(before.text.splitlines())
    return [
        line.strip("│ ").split("── ", 1)[1].split(" ──")[0].strip()  # may be cut at the edge
        for line in now.text.splitlines()
        if line.startswith("│") and "── " in line and line not in old
    ]


def new_gap_in_log(before: View) -> Check:
    """A check: a new mark in the console's frame log that says the connection was lost."""

    def check(view: View) -> str | None:
        return next((gap for gap in gaps_in_log(before, view) if "lost" in gap), None)

    return check


def watch_failed(view: View) -> str | None:
    for line in view.lines:
        if line.get("ok") is False:
            errors = line.get("errors") or {}
            first = next(iter(errors.items()), ("", ""))
            return f'"ok": false, {first[0]}: {first[1]}'
    return None


def watch_fresh(view: View) -> str | None:
    for line in view.lines:
        values = line.get("values") or {}
        if line.get("ok") is True and all(isinstance(v, int) for v in values.values()):
            return f'"ok": true, {len(values)} values'
    return None


def repl_says_lost(view: View) -> str | None:
    """The REPL at its prompt: ``not connected>``, or a line or toolbar saying so, after
    the last command's result."""
    lines = [line for line in view.text.splitlines() if line.strip()]
    for line in lines[-3:]:
        lowered = line.lower()
        if "not connected>" in lowered:
            return "prompt: not connected>"
        if any(word in lowered for word in ("lost", "disconnected", "closed")):
            return line.strip()[:60]
    return None


@dataclass
class Row:
    case: str
    client: str
    who: str  # the client, as the attribution count names it
    loss: str = "–"
    recover: str = "–"
    wrong_writes: int = 0
    shown: str = ""


class Bench:
    """The run: namespaces, controller, clients, cases and the table."""

    def __init__(self, deadline: float, hold: float, verbose: bool) -> None:
        self.deadline, self.hold, self.verbose = deadline, hold, verbose
        self.net = Net(str(os.getpid()))
        self._scratch = tempfile.TemporaryDirectory(prefix="racnet-")
        self.scratch = Path(self._scratch.name)
        self.env = client_env(self.scratch)
        self.attribution = Attribution()
        self.controller = Controller(self.net, self.scratch, self.env)
        self.console: ConsoleView | None = None
        self.repl: ReplView | None = None
        self.watch: WatchStream | None = None
        self.rows: list[Row] = []
        self.cases: list[str] = []
        self.notes: list[str] = []

    # ------------------------------------------------------------ set-up

    def start(self) -> None:
        """The controller in A, preset; the console and the REPL in B, connected."""
        self.controller.start()
        self.controller.preset()
        history = str(self.scratch / "history")
        base = [*RAC, "-H", SIM_HOST, "--history", history]
        self.console = ConsoleView(
            self.net, "console", base, self.env, self.scratch, self.attribution
        )
        self.repl = ReplView(
            self.net, "repl", [*base, "repl"], self.env, self.scratch, self.attribution
        )
        self.console.start()
        self.repl.start()
        started = self.wait(
            {
                "console": (self.console, state_connected),
                "REPL": (
                    self.repl,
                    lambda v: "prompt" if f"{SIM_HOST}:{PORT}>" in v.text else None,
                ),
            },
            30,
        )
        for name, when in started.items():
            if when is None:
                raise RuntimeError(f"the {name} did not start: {self._pane(name).screen()[-800:]}")

    def _pane(self, name: str) -> Pane:
        pane = self.console if name == "console" else self.repl
        assert pane is not None
        return pane

    def down(self) -> None:
        if self.watch is not None:
            self.watch.stop()
        for pane in (self.console, self.repl):
            if pane is not None:
                pane.stop()
        self.controller.kill()
        self.net.down()
        self._scratch.cleanup()

    # ------------------------------------------------------------ looking

    def wait(
        self,
        checks: Checks,
        limit: float,
        since: float | None = None,
    ) -> dict[str, tuple[float, str] | None]:
        """Look at every client every SAMPLE_EVERY s until each check has held once or
        ``limit`` s passed: for each, (seconds since ``since``, what it showed), or None."""
        start = time.monotonic() if since is None else since
        found: dict[str, tuple[float, str] | None] = dict.fromkeys(checks)
        trail: dict[str, str] = {}
        while True:
            now = time.monotonic()
            clients = {id(client): client for client, _ in checks.values()}
            views = {key: client.look() for key, client in clients.items()}
            for name, (client, check) in checks.items():
                view = views[id(client)]
                if self.verbose:
                    self._trail(name, view, now - start, trail)
                if found[name] is None:
                    said = check(view)
                    if said is not None:
                        found[name] = (now - start, said)
            if all(found.values()) or now - start >= limit:
                if self.verbose:  # what a client showed instead, where a sign never came
                    for name in (name for name, when in found.items() if when is None):
                        shown = views[id(checks[name][0])].text or "(no screen)"
                        print(f"    {name}, not shown; its screen:\n{shown}", flush=True)
                return found
            time.sleep(SAMPLE_EVERY)

    def _trail(self, name: str, view: View, at: float, trail: dict[str, str]) -> None:
        """--verbose: each change of what a client shows, timed."""
        statuses = Counter(status for status, _ in view.rows.values())
        shown = " ".join(f"{n}x{s}" for s, n in sorted(statuses.items()))
        if view.state:
            shown = f"[{view.state}] {shown}"
        for line in view.lines:
            shown = f"ok={line.get('ok')} {sorted(set((line.get('errors') or {}).values()))}"
        if shown and trail.get(name) != shown:
            trail[name] = shown
            print(f"    {at:6.2f} s  {name}: {shown}", flush=True)

    def clients(self) -> tuple[ConsoleView, ReplView]:
        assert self.console is not None and self.repl is not None
        return self.console, self.repl

    def begin(self, case: str) -> None:
        self.cases.append(case)
        self.attribution.case = case
        if self.verbose:
            print(f"  -- {case}", flush=True)

    def add(
        self,
        case: str,
        client: str,
        who: str,
        loss: tuple[float, str] | str | None,
        recover: tuple[float, str] | str | None,
        limit: float,
        shown: str = "",
        wrong_writes: int = 0,
    ) -> None:
        def cell(what: tuple[float, str] | str | None) -> str:
            if isinstance(what, str):
                return what
            return f"{what[0]:.1f} s" if what else f"not shown within {limit:g} s"

        if not shown:
            shown = "; ".join(w[1] for w in (loss, recover) if isinstance(w, tuple))
        self.rows.append(Row(case, client, who, cell(loss), cell(recover), wrong_writes, shown))

    # ------------------------------------------------------------ cases

    def pulled_while_polling(self) -> None:
        case = "pulled while polling"
        self.begin(case)
        console, repl = self.clients()
        console.type(f"watch I {WATCHED[0]}-{WATCHED[-1]}")
        repl.type(f"watch I {WATCHED[0]}-{WATCHED[-1]}")
        self.watch = watch = WatchStream(self.net, self.env, self.scratch, self.attribution)
        ready = self.wait(
            {
                "console": (console, rows_all_ok),
                "REPL": (repl, rows_all_ok),
                "watch": (watch, watch_fresh),
            },
            30,
        )
        if not all(ready.values()):
            self.notes.append(f"{case}: not all clients polled before the pull: {ready}")
        who = {
            "console: rows": "console",
            "console: status line": "console",
            "REPL": "REPL",
            "watch --json": "watch",
        }
        checks_lost: Checks = {
            "console: rows": (console, rows_not_ok),
            "console: status line": (console, state_not_connected),
            "REPL": (repl, rows_not_ok),
            "watch --json": (watch, watch_failed),
        }
        checks_back: Checks = {
            "console: rows": (console, rows_all_ok),
            "console: status line": (console, state_connected),
            "REPL": (repl, rows_all_ok),
            "watch --json": (watch, watch_fresh),
        }
        pulled = time.monotonic()
        self.net.pull()
        lost = self.wait(checks_lost, self.deadline, since=pulled)
        while time.monotonic() < pulled + self.hold:  # the cable stays out a while
            for client in (console, repl, watch):
                client.look()  # what they show still counts
            time.sleep(SAMPLE_EVERY)
        restored = time.monotonic()
        self.net.restore()
        back = self.wait(checks_back, self.deadline, since=restored)
        for name in checks_lost:
            self.add(case, name, who[name], lost[name], back[name], self.deadline)
        watch.stop()
        self.watch = None
        repl.type_keys("Enter")  # leave the live table
        console.type("unwatch all")
        time.sleep(1)

    def pulled_while_idle(self) -> None:
        case = "pulled while idle"
        self.begin(case)
        console, repl = self.clients()
        for pane in (console, repl):
            pane.type("get I 11")
        answered = self.wait(
            {
                "console": (console, answer(console, "get I 11", 11)),
                "REPL": (repl, answer(repl, "get I 11", 11)),
            },
            15,
        )
        if not all(answered.values()):
            self.notes.append(f"{case}: get I 11 before the pull: {answered}")
        time.sleep(1)
        at_pull = console.look()
        pulled = time.monotonic()
        self.net.pull()
        lost = self.wait(
            {
                "console: status line": (console, state_not_connected),
                "console: frame log": (console, new_gap_in_log(at_pull)),
                "REPL": (repl, repl_says_lost),
            },
            self.deadline,
            since=pulled,
        )
        redrawn = ""
        if lost["REPL"] is None:  # prompt_toolkit redraws on a key: what would a key show?
            repl.type_keys("x", "BSpace")
            time.sleep(0.5)
            bottom = [line.strip() for line in repl.screen().splitlines() if line.strip()][-2:]
            redrawn = "nothing; after a key: " + " / ".join(bottom)
        restored = time.monotonic()
        self.net.restore()
        for pane in (console, repl):
            pane.type("get I 13")
        back = self.wait(
            {
                "console": (console, answer(console, "get I 13", 13)),
                "REPL": (repl, answer(repl, "get I 13", 13)),
            },
            self.deadline,
            since=restored,
        )
        for name, client in (
            ("console: status line", "console"),
            ("console: frame log", "console"),
            ("REPL", "REPL"),
        ):
            shown = redrawn if name == "REPL" else ""
            self.add(case, name, client, lost[name], back[client], self.deadline, shown=shown)

    def rebooted_while_out(self) -> None:
        case = "rebooted while the cable was out"
        self.begin(case)
        console, repl = self.clients()
        for pane in (console, repl):
            pane.type("get I 14")
        self.wait(
            {
                "console": (console, answer(console, "get I 14", 14)),
                "REPL": (repl, answer(repl, "get I 14", 14)),
            },
            15,
        )
        at_pull = console.look()
        self.net.pull()
        self.controller.kill()
        self.controller.start()
        self.controller.preset()  # over A's loopback: the new controller holds 1000 + k
        restored = time.monotonic()
        self.net.restore()
        for pane in (console, repl):
            pane.type("get I 12")
        back = self.wait(
            {
                "console": (console, answer(console, "get I 12", 12, True)),
                "REPL": (repl, answer(repl, "get I 12", 12, True)),
            },
            self.deadline,
            since=restored,
        )
        gaps = gaps_in_log(at_pull, console.look())
        for name in ("console", "REPL"):
            got = back[name]
            ok = got is not None and got[1].startswith(f"I12 = {expected(12)}")
            said = f"first get: {'yes' if ok else 'no'}"
            said += f" ({got[1][:60]})" if got else " (nothing shown)"
            if name == "console" and gaps:
                said += f"; log: {' / '.join(gaps)}"
            self.add(case, name, name, "–", got, self.deadline, shown=said)

    def put_case(self, case: str, pull: Callable[[], None]) -> None:
        """A CLI PUT with the cable pulled by ``pull``; restored after it reports, then
        SETTLE_AFTER_PUT s for anything held up to land; the report against the value."""
        self.begin(case)
        self.controller.put_values({PUT_INDEX: expected(PUT_INDEX)})
        pull()
        started = time.monotonic()
        argv = self.net.in_b(
            *RAC,
            "-H",
            SIM_HOST,
            "--timeout",
            "1",
            "--json",
            "put",
            "I",
            str(PUT_INDEX),
            str(PUT_VALUE),
        )
        report: dict[str, Any] | None = None
        status: int | str
        try:
            done = subprocess.run(
                argv,
                capture_output=True,
                text=True,
                env=self.env,
                cwd=self.scratch,
                timeout=self.deadline,
            )
            status = done.returncode
            with contextlib.suppress(ValueError, IndexError):
                report = json.loads(done.stdout.strip().splitlines()[-1])
        except subprocess.TimeoutExpired:
            status = "none"
        took = time.monotonic() - started
        self.net.restore()
        time.sleep(SETTLE_AFTER_PUT)
        final = self.controller.read(PUT_INDEX)
        wrong, verdict = judge_write(report, final)
        for value in (report or {}).get("before"), (report or {}).get("read_back"):
            if isinstance(value, int) and value not in (expected(PUT_INDEX), PUT_VALUE):
                self.attribution.wrong[(case, "CLI put")] += 1
                self.attribution.examples.append(f"{case}: the PUT's report holds {value}")
        reported = "nothing" if report is None else describe_write(report)
        shown = f"{reported}, exit {status}; I{PUT_INDEX} then {final}: {verdict}"
        self.add(
            case,
            "CLI put --timeout 1",
            "CLI put",
            (took, "reported"),
            "–",
            self.deadline,
            shown=shown,
            wrong_writes=int(wrong),
        )

    # ------------------------------------------------------------ table

    def table(self) -> tuple[int, int]:
        """The table, a legend, notes; the wrong attributions and wrong write reports."""
        wrong_attr = sum(self.attribution.wrong.values())
        head = (
            "case",
            "client",
            "shows the loss",
            "recovers",
            "wrong attr.",
            "wrong writes",
            "what it showed",
        )
        cells = [
            (
                r.case,
                r.client,
                r.loss,
                r.recover,
                str(self.attribution.wrong[(r.case, r.who)]),
                str(r.wrong_writes),
                r.shown,
            )
            for r in self.rows
        ]
        widths = [max(len(h), *(len(c[n]) for c in cells)) for n, h in enumerate(head)]
        widths[-1] = len(head[-1])
        print("| " + " | ".join(h.ljust(w) for h, w in zip(head, widths, strict=True)) + " |")
        print("|" + "|".join("-" * (w + 2) for w in widths) + "|")
        for c in cells:
            print("| " + " | ".join(v.ljust(w) for v, w in zip(c, widths, strict=True)) + " |")
        print(
            "shows the loss: seconds from the pull (a PUT: until the CLI reported); recovers: "
            "seconds from the restore until fresh values (polling) or the answer to the first "
            "command typed (idle, rebooted)"
        )
        for line in self.attribution.examples[:10] + self.notes:
            print(f"  note: {line}")
        return wrong_attr, sum(r.wrong_writes for r in self.rows)


def answer(pane: Pane, typed: str, index: int, any_result: bool = False) -> Check:
    """A check: the result printed after ``typed``; a value is fed to the attribution
    count. Unless ``any_result``, only a value counts (an error is not the answer)."""

    def check(view: View) -> str | None:
        said = pane.result_of(typed)
        if said is None:
            return None
        value = re.match(rf"I{index} = (-?\d+)", said)
        if value:
            pane_name = "console" if isinstance(pane, ConsoleView) else "REPL"
            pane.attribution.see(pane_name, index, int(value.group(1)), every=True)
            return said
        return said if any_result else None

    return check


def describe_write(report: dict[str, Any]) -> str:
    error = str(report.get("error") or "")
    if "not sent" in error:
        return "not sent"
    if "outcome unknown" in error:
        what = "outcome unknown"
    else:
        what = str(report.get("result_name") or ("ok" if report.get("ok") else error[:40]))
    return f"{what}, verified {json.dumps(report.get('verified'))}"


def judge_write(report: dict[str, Any] | None, final: int | None) -> tuple[bool, str]:
    """Whether the PUT's report was wrong about what the controller holds afterwards:
    ``verified`` true needs 7777, false needs anything else, null ("outcome unknown")
    is honest whatever the value; "not sent" needs the value untouched."""
    if final is None:
        return False, "value unreadable"
    if report is None:
        return False, "no report to judge"
    landed = final == PUT_VALUE
    error = str(report.get("error") or "")
    verified = report.get("verified")
    if "not sent" in error:
        return landed, "WRONG: said not sent, but it landed" if landed else "agrees"
    if verified is True and not landed:
        return True, "WRONG: verified, but the value is not there"
    if verified is False and landed:
        return True, "WRONG: verified false, but the value landed"
    if report.get("ok") and not landed and verified is not False:
        return True, "WRONG: S_OK, but the value is not there"
    return False, "agrees" if verified is not None or report.get("ok") else "honest (unknown)"


def client_env(home: Path) -> dict[str, str]:
    """The clients' history, settings and profiles in the scratch folder, not the user's;
    no COLUMNS or LINES (pytest's children get 80x24), so the panes' size is what counts."""
    dropped = ("RAC_CONSOLE_CONFIG", "COLUMNS", "LINES")
    env = {k: v for k, v in os.environ.items() if k not in dropped}
    for name in ("CONFIG", "STATE", "DATA", "CACHE"):
        env[f"XDG_{name}_HOME"] = str(home / name.lower())
    env["HOME"] = str(home)
    return env


@contextlib.contextmanager
def interrupts_end_cleanly() -> Iterator[None]:
    """SIGINT and SIGTERM unwind as Ctrl-C does, so ``finally`` tears the namespaces
    down; SIGINT even when started ignoring it (in the background of a script)."""

    def stop(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="shorter deadlines and no hold: about a minute and a half",
    )
    parser.add_argument(
        "--deadline", type=float, help="seconds to wait for each sign (60; quick 20)"
    )
    parser.add_argument(
        "--hold",
        type=float,
        help="seconds the cable stays out while polling (20; quick: until shown)",
    )
    parser.add_argument(
        "--verbose", action="store_true", help="print each change each client shows"
    )
    args = parser.parse_args()
    deadline = args.deadline or (20.0 if args.quick else 60.0)
    hold = args.hold if args.hold is not None else (0.0 if args.quick else 20.0)

    reason = why_not()
    bench: Bench | None = None
    with interrupts_end_cleanly():
        try:
            if reason is None:
                bench = Bench(deadline, hold, args.verbose)
                try:
                    bench.net.up()
                except (subprocess.SubprocessError, OSError) as exc:
                    reason = f"cannot make network namespaces: {failure(exc)}"
            if reason is not None or bench is None:
                print(f"network paths: skipped: {reason}")
                return 0
            started = time.monotonic()
            print(
                f"namespaces {bench.net.a} (controller {SIM_HOST}:{PORT}) and {bench.net.b} "
                f"(clients {CLIENT_HOST}); the cable pulled in {bench.net.a} on "
                f"{bench.net.veth_a}; deadline {deadline:g} s, hold {hold:g} s",
                flush=True,
            )
            bench.start()
            bench.pulled_while_polling()
            bench.pulled_while_idle()
            bench.rebooted_while_out()
            bench.put_case("PUT with the cable pulled", bench.net.pull)
            missing = bench.net.can_pull_at_put()
            if missing is None:
                bench.put_case("PUT, cable out as it lands", lambda: bench.net.pull_at_put(False))
                bench.put_case(
                    "PUT, cable out before it lands", lambda: bench.net.pull_at_put(True)
                )
            else:
                bench.notes.append(f"PUT in flight cases skipped: {missing}")
            print()
            wrong_attr, wrong_writes = bench.table()
            print(f"({time.monotonic() - started:.0f} s)")
            print(
                f"network paths: {len(bench.cases)} cases, wrong attributions {wrong_attr}, "
                f"wrong write reports {wrong_writes}"
            )
            return 0
        except KeyboardInterrupt:
            print("network paths: interrupted; removing the namespaces", file=sys.stderr)
            return 130
        except (RuntimeError, subprocess.SubprocessError, OSError) as exc:
            print(f"network paths: failed: {failure(exc)}", file=sys.stderr)
            return 1
        finally:
            if bench is not None:
                bench.down()


if __name__ == "__main__":
    sys.exit(main())
