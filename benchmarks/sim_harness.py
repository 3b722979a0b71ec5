"""The simulator as a subprocess, and clients that misbehave: shared by
``benchmarks/sim_abuse.py`` (full counts, figures) and ``tests/test_sim_abuse.py``
(small counts, assertions).

Every client talks only to 127.0.0.1, is bounded in time, and closes what it opened.
"""

from __future__ import annotations

import contextlib
import os
import queue
import re
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO

HOST = "127.0.0.1"
REQUEST = b"GET:RC8:1:P:\r"
PROBE = b"GET:RC8:1:S:\r"
PROBE_REPLY = b"0,8,RC8 simulator\r"


def ask(port: int, deadline: float, sock: socket.socket | None = None) -> float | None:
    """Seconds to get the probe's reply (on a new connection unless given), None if not
    answered within ``deadline`` seconds."""
    started = time.perf_counter()
    own = sock is None
    try:
        if sock is None:
            sock = socket.create_connection((HOST, port), timeout=deadline)
        sock.settimeout(deadline)
        sock.sendall(PROBE)
        reply = b""
        while not reply.endswith(b"\r"):
            remaining = deadline - (time.perf_counter() - started)
            if remaining <= 0:
                return None
            sock.settimeout(remaining)
            chunk = sock.recv(100)
            if not chunk:
                return None
            reply += chunk
        return time.perf_counter() - started if reply == PROBE_REPLY else None
    except OSError:
        return None
    finally:
        if own and sock is not None:
            sock.close()


def linger_reset(sock: socket.socket) -> None:
    """Close with an RST instead of a FIN."""
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")


def hostile(port: int, n: int) -> None:
    """One short hostile connection of kind ``n % 4``."""
    try:
        sock = socket.create_connection((HOST, port), timeout=5)
    except OSError:
        return
    with sock, contextlib.suppress(OSError):
        kind = n % 4
        if kind == 0:  # junk: binary, no CR within 256 bytes
            sock.sendall(os.urandom(300 + n % 3000))
        elif kind == 1:  # a partial line, then gone (every other one with an RST)
            sock.sendall(b"GET:RC8:1")
            if n % 8 == 1:
                linger_reset(sock)
        elif kind == 2:  # 50 pipelined requests, then close without reading
            sock.sendall(REQUEST * 50)
        else:  # a request, then half-close; close without reading the answer
            sock.sendall(PROBE)
            sock.shutdown(socket.SHUT_WR)


class SimulatorProcess:
    """``python -m rac_console sim --port 0 ARGS``, stderr to a file or to a pipe nobody
    reads; killed on exit. It runs in a scratch folder, so ``pythonpath`` (or the
    environment's PYTHONPATH) decides which copy of the package runs. ``profile``: it
    runs under cProfile, interrupted (not killed) on exit so the profile is written
    there. RSS, descriptors and CPU are read from /proc (Linux)."""

    def __init__(
        self,
        *args: str,
        stderr_pipe: bool = False,
        preexec: Callable[[], None] | None = None,
        pythonpath: str | None = None,
        profile: Path | None = None,
    ) -> None:
        self._scratch = tempfile.TemporaryDirectory()
        self.err_path = Path(self._scratch.name) / "stderr"
        self._err: IO[bytes] | None = None if stderr_pipe else open(self.err_path, "wb")  # noqa: SIM115
        env = dict(os.environ)
        if pythonpath:
            env["PYTHONPATH"] = os.pathsep.join(filter(None, [pythonpath, env.get("PYTHONPATH")]))
        self._profile = profile
        profiler = ["-m", "cProfile", "-o", str(Path(profile).resolve())] if profile else []
        self.process = subprocess.Popen(
            [sys.executable, *profiler, "-m", "rac_console", "sim", "--port", "0", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE if stderr_pipe else self._err,
            cwd=self._scratch.name,
            env=env,
            preexec_fn=preexec,
        )
        lines: queue.Queue[bytes] = queue.Queue()
        stdout = self.process.stdout
        assert stdout is not None
        threading.Thread(target=lambda: lines.put(stdout.readline()), daemon=True).start()
        try:
            first = lines.get(timeout=20).decode()
        except queue.Empty:
            first = ""
        found = re.search(r"listening on .*:(\d+) ", first)
        if not found:
            self.stop()
            raise RuntimeError(f"the simulator did not start: {first!r} {self.stderr()[:500]!r}")
        self.port = int(found.group(1))

    @property
    def pid(self) -> int:
        return self.process.pid

    def stderr(self) -> str:
        if self._err is None:
            return ""
        self._err.flush()
        return self.err_path.read_text(errors="replace")

    def rss_kb(self, field: str = "VmRSS") -> int:
        for line in Path(f"/proc/{self.pid}/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1])
        raise RuntimeError(f"no {field} in /proc/{self.pid}/status")

    def fds(self) -> int:
        return len(os.listdir(f"/proc/{self.pid}/fd"))

    def cpu_seconds(self) -> float:
        fields = Path(f"/proc/{self.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def stop(self) -> None:
        if self._profile is not None and self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)  # Ctrl-C: cProfile writes its file
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(30)
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(10)
        for stream in (self.process.stdout, self.process.stderr, self._err):
            if stream is not None:
                stream.close()
        self._scratch.cleanup()

    def __enter__(self) -> SimulatorProcess:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()
