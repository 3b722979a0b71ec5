"""The OPC UA server of ``--opcua``: the watched values, served to SCADA.

The server runs in a process of its own (:mod:`.opcua_space`): a client that browses
and subscribes flat out takes that process's time and interpreter lock, not the polls'
(on a thread of this process, four such clients made the polls at 0.2 s come every
0.5 s). Engines hand their rows to :class:`OpcUaServer` as they change (any thread,
never waiting): the latest of each variable is kept, and a thread of its own sends them
at once, together. A client's write comes back from that process and goes to the
engine of its target, which holds the write gate (:mod:`..engine.polling.plant_writes`).
"""

from __future__ import annotations

import contextlib
import subprocess
import sys
import threading
from collections.abc import Callable, Iterable
from concurrent.futures import Future
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from ..commands.language import VarRef
from ..commands.opcua import OpcUaSettings
from ..protocol import InputError, kind_of
from ..protocol.text import terminal_safe
from .opcua_pipe import ENDED, FORGET, Pipe, Row, plain

if TYPE_CHECKING:
    from ..protocol import Variant

#: How long the server's process may take to start listening.
START_DEADLINE = 60.0


class PlantWrites(Protocol):
    """Where a target's writes go (the engine's, see engine/polling/plant_writes.py):
    the answer is an OPC UA status name and what was said."""

    def write(self, var: VarRef, text: str) -> Future[tuple[str, str]]: ...


class RowView(Protocol):
    """A watched row as an engine publishes it."""

    @property
    def var(self) -> VarRef: ...
    @property
    def label(self) -> str: ...
    @property
    def variant(self) -> Variant | None: ...
    @property
    def status(self) -> str: ...
    @property
    def stale(self) -> bool: ...


class OpcUaServer:
    """Start with :meth:`start` (InputError: it cannot listen); stop with :meth:`stop`."""

    def __init__(self, settings: OpcUaSettings) -> None:
        self.settings = settings
        self.port = settings.address.port
        self.certificate: str | None = None  # its path, when the server has one
        self.certificate_made = False  # made at this start
        self._lock = threading.Lock()
        self._pending: dict[tuple[str, str], Row | str | None] = {}
        self._out: list[list[Any]] = []  # answers to send
        self._wake = threading.Event()
        self._writers: dict[str, PlantWrites | None] = {}
        self._says: dict[str, Callable[[str], None]] = {}
        self._process: subprocess.Popen[bytes] | None = None
        self._pipe: Pipe | None = None
        self._stopping = False

    def __str__(self) -> str:
        host = self.settings.address.host
        return f"opc.tcp://{f'[{host}]' if ':' in host else host}:{self.port}"

    # ------------------------------------------------------------ start and stop

    def start(self) -> None:
        """Start the server's process and wait until it listens."""
        # -P: not the current folder's modules first. Its own process group: Ctrl-C at
        # the REPL is the REPL's, not the server's. Below the polls' priority.
        flags = getattr(subprocess, "CREATE_NO_WINDOW", 0)
        flags |= getattr(subprocess, "CREATE_NEW_PROCESS_GROUP", 0)
        flags |= getattr(subprocess, "BELOW_NORMAL_PRIORITY_CLASS", 0)
        self._process = process = subprocess.Popen(
            [sys.executable, "-P", "-m", "rac_console.plant.opcua_space"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=_child_environment(Path(__file__).resolve().parents[2]),
            creationflags=flags,
            start_new_session=sys.platform != "win32",
        )
        assert process.stdin is not None and process.stdout is not None
        self._pipe = pipe = Pipe(process.stdout, process.stdin)  # type: ignore[arg-type]
        s = self.settings
        address = s.address
        pipe.send(["settings", address.host, address.port, s.security.value, s.writes,
                   s.username, s.password])  # fmt: skip
        first: list[list[Any] | None] = []
        waiting = threading.Thread(target=lambda: first.append(pipe.receive()), daemon=True)
        waiting.start()
        waiting.join(START_DEADLINE)
        message = first[0] if first else None
        if message is None or message[0] != "ready":
            self.stop()
            said = message[1] if message is not None and message[0] == "failed" else None
            raise InputError(terminal_safe(said or f"the OPC UA server at {self} did not start"))
        self.port, self.certificate, self.certificate_made = message[1], message[2], message[3]
        threading.Thread(target=self._read, name="rac-opcua-in", daemon=True).start()
        threading.Thread(target=self._send, name="rac-opcua-out", daemon=True).start()

    def stop(self) -> None:
        self._stopping = True
        process, pipe = self._process, self._pipe
        if process is None:
            return
        if pipe is not None:
            with contextlib.suppress(OSError, ValueError):
                pipe.send(["stop"])
        try:
            process.wait(10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(10)
        self._wake.set()

    # ------------------------------------------------------------ the engines' side

    def attach(self, target: str, writes: PlantWrites | None, say: Callable[[str], None]) -> None:
        """An engine serves ``target``'s values (and takes its writes); ``say`` tells
        its user what became of a client's write (any thread)."""
        with self._lock:
            self._writers[target] = writes
            self._says[target] = say

    def detach(self, target: str, forget: bool = False) -> None:
        """The engine of ``target`` ended: its values go Bad (``forget``: its folder goes,
        the engine now reading another target)."""
        with self._lock:
            self._writers.pop(target, None)
            self._says.pop(target, None)
            self._queue((target, ""), FORGET if forget else ENDED)
        self._wake.set()

    def update(self, target: str, views: Iterable[RowView], wall: float) -> None:
        """Rows whose value or health changed (the engine's thread): kept, sent at once."""
        with self._lock:
            for view in views:
                var, variant = view.var, view.variant
                value = plain(variant.value) if variant is not None else None
                unsent = variant is not None and value is None  # a value no kind served holds
                stale = view.stale or unsent
                row: Row = (var.kind.code, var.index, view.label, value, view.status, stale, wall)
                self._queue((target, str(var)), row)
        self._wake.set()

    def paused(self, target: str, paused: bool) -> None:
        """The target's polling paused (its values no longer read: not Good) or resumed."""
        with self._lock:
            self._out.append(["paused", target, paused])
        self._wake.set()

    def remove(self, target: str, variables: Iterable[VarRef]) -> None:
        """Rows unwatched: their variables leave the address space."""
        with self._lock:
            for var in variables:
                self._queue((target, str(var)), None)
        self._wake.set()

    def _queue(self, key: tuple[str, str], what: Row | str | None) -> None:
        self._pending.pop(key, None)  # sent in the order of the last news of each
        self._pending[key] = what

    # ------------------------------------------------------------ the pipe's threads

    def _send(self) -> None:
        pipe = self._pipe
        assert pipe is not None
        while not self._stopping:
            self._wake.wait()
            self._wake.clear()
            with self._lock:
                pending, self._pending = self._pending, {}
                out, self._out = self._out, []
            try:
                if pending:
                    pipe.send(["rows", [[t, k, row] for (t, k), row in pending.items()]])
                for message in out:
                    pipe.send(message)
            except (OSError, ValueError):  # the server's process has gone (said by _read)
                return

    def _read(self) -> None:
        pipe = self._pipe
        assert pipe is not None
        try:
            while (message := pipe.receive()) is not None:
                if message[0] == "say":
                    self._say(str(message[1]), message[2])
                elif message[0] == "write":
                    self._write(*message[1:])
        except Exception as exc:  # never a traceback over the console: said, and ended
            self._say(f"the OPC UA server at {self}: {exc!r}")
        if self._process is not None and self._process.poll() is None:
            self._process.kill()  # nobody reads it any more: it must not wait on us
        if not self._stopping:
            self._say(f"the OPC UA server at {self} stopped: its process ended")

    def _say(self, text: str, target: str | None = None) -> None:
        """Told to the user of ``target`` (else of the first target served)."""
        with self._lock:
            say = self._says.get(target or "") or next(iter(self._says.values()), None)
        if say is not None:
            say(terminal_safe(text))

    def _write(self, number: int, target: str, code: str, index: int, text: str) -> None:
        with self._lock:
            writes = self._writers.get(target)

        def answer(status: str, said: str) -> None:
            with self._lock:
                self._out.append(["answer", number, status, said])
            self._wake.set()

        if writes is None:
            answer("BadNotWritable", f"{target} is not read by anything now")
            return
        try:
            var = VarRef(kind_of(code), index)
        except InputError:
            answer("BadNodeIdUnknown", f"{code}{index}")
            return
        writes.write(var, text).add_done_callback(lambda done: answer(*done.result()))


def _child_environment(root: Path) -> dict[str, str]:
    """This environment without the password (it goes over the pipe), and the package
    importable when it was loaded from a zip (installed, or a checkout on the path, the
    same interpreter finds it)."""
    import os

    from ..commands.opcua import PASSWORD_ENV

    env = {name: value for name, value in os.environ.items() if name != PASSWORD_ENV}
    if root.is_file():
        paths = [str(root), *filter(None, env.get("PYTHONPATH", "").split(os.pathsep))]
        env["PYTHONPATH"] = os.pathsep.join(paths)
    return env
