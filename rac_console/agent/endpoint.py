"""Where the agent listens, reachable by its user on this machine only.

On Linux and macOS: a Unix socket, mode 0600, in a folder of the user's (0700) under the
user's runtime folder (``$XDG_RUNTIME_DIR/rac-console`` on Linux), and a peer of another
user is turned away even if it got that far (its credentials are asked of the kernel).
On Windows, where asyncio and older Pythons have no Unix sockets: a TCP port on
127.0.0.1 and a token in a file of the user's folder; a client proves it read the file.
Nothing listens on another address.

A socket left by an agent that died is no agent: connecting to it is refused, so a
client goes direct at once, and the next agent takes its place.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import socket
import stat
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING

if TYPE_CHECKING:
    from .wire import Channel

#: How long a client waits to reach an agent that is there (a local socket: at once).
CONNECT_TIMEOUT = 2.0
#: How often the agent's accept loop wakes to see whether it should stop.
ACCEPT_WAKE = 0.2
SOCKET_NAME = "agent.sock"
PORT_FILE = "agent.json"  # Windows: the port and the token
LOCK_NAME = "agent.lock"  # held by the running agent
WINDOWS = sys.platform == "win32"


class EndpointError(OSError):
    """The agent's folder or socket cannot be made safely (said in one line)."""


def folder() -> Path:
    """The user's own folder for the agent's endpoint, made 0700 if it is not there;
    refused when it is another user's or others can write it."""
    override = os.environ.get("RAC_CONSOLE_AGENT_DIR")
    base = Path(override) if override else _runtime_base()
    if base.is_symlink():  # planted in /tmp by another: never followed
        raise EndpointError(f"{base} is a symbolic link: the agent will not use it")
    if base.exists() and not base.is_dir():
        raise EndpointError(
            f"{base} is a file, not a folder: the agent's folder must be one "
            "(RAC_CONSOLE_AGENT_DIR names it)"
        )
    base.mkdir(mode=0o700, parents=True, exist_ok=True)
    if not WINDOWS:
        info = os.lstat(base)
        if info.st_uid != os.getuid():
            raise EndpointError(f"{base} belongs to another user: the agent will not use it")
        if stat.S_IMODE(info.st_mode) & 0o077:
            base.chmod(0o700)
    return base


def _runtime_base() -> Path:
    """The user's runtime folder for the agent (not made here)."""
    if WINDOWS:
        from platformdirs import user_runtime_dir

        return Path(user_runtime_dir("rac-console", appauthor=False))
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime and Path(runtime).is_dir():
        return Path(runtime) / "rac-console"
    if sys.platform == "darwin":
        from platformdirs import user_runtime_dir

        return Path(user_runtime_dir("rac-console"))
    # No runtime folder (a bare ssh or su session): one of the user's in /tmp.
    return Path(tempfile.gettempdir()) / f"rac-console-{os.getuid()}"


@dataclass(frozen=True)
class Endpoint:
    """Where the agent is: a socket's path, or (Windows) a port with its token."""

    path: Path | None = None
    port: int | None = None
    token: str = ""

    def __str__(self) -> str:
        return str(self.path) if self.path is not None else f"127.0.0.1:{self.port}"


class Listener:
    """The agent's listening socket: each client as a :class:`~.wire.Channel`; and the
    lock that makes it the only agent of its folder (held until :meth:`close`)."""

    def __init__(self, server: socket.socket, lock: IO[bytes] | None = None) -> None:
        self._server = server
        self._lock = lock
        server.settimeout(ACCEPT_WAKE)

    def accept(self) -> Channel | None:
        """The next client, or None after :data:`ACCEPT_WAKE` seconds without one;
        OSError once closed."""
        from .wire import Channel

        try:
            sock, _ = self._server.accept()
        except TimeoutError:
            return None
        sock.settimeout(None)
        return Channel(sock)

    def close(self) -> None:
        self._server.close()
        if self._lock is not None:
            self._lock.close()  # the lock goes with it


def listen() -> tuple[Listener, Endpoint]:
    """The agent's listener (see :func:`listen_socket`), once it holds the folder's
    lock: of two agents started at once, the second is told one is running (it would
    otherwise take the first one's socket or port file while the first still starts)."""
    lock = _lock(folder())
    try:
        server, endpoint = listen_socket()
    except BaseException:
        lock.close()
        raise
    return Listener(server, lock), endpoint


def _lock(base: Path) -> IO[bytes]:
    """The folder's lock file, held (EndpointError when another agent holds it)."""
    held = open(base / LOCK_NAME, "ab")  # noqa: SIM115 - held for the agent's life
    try:
        if sys.platform == "win32":
            import msvcrt

            held.seek(0)
            msvcrt.locking(held.fileno(), msvcrt.LK_NBLCK, 1)
        else:
            import fcntl

            fcntl.flock(held.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        held.close()
        raise EndpointError(
            f"an agent is already running (it holds {base / LOCK_NAME}): rac-console agent "
            "status says which; stop it first (Ctrl-C where it runs, or kill its pid)"
        ) from None
    return held


def listen_socket() -> tuple[socket.socket, Endpoint]:
    """The agent's listening socket; a socket left by a dead agent is replaced, a
    living agent's is not (EndpointError says it is running)."""
    base = folder()
    if WINDOWS:
        return _listen_tcp(base)
    path = base / SOCKET_NAME
    if path.exists() or path.is_symlink():
        if _alive(path):
            raise EndpointError(f"an agent is already running ({path})")
        path.unlink()
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    old = os.umask(0o177)  # made 0600: no moment when another user could connect
    try:
        server.bind(str(path))
    except OSError as exc:  # a path too long for a socket, a folder that went
        server.close()
        raise EndpointError(f"cannot listen on {path}: {exc.strerror or exc}") from None
    finally:
        os.umask(old)
    path.chmod(0o600)
    server.listen(16)
    return server, Endpoint(path=path)


def _listen_tcp(base: Path) -> tuple[socket.socket, Endpoint]:
    found = _read_port_file(base / PORT_FILE)
    if found is not None and _reach_tcp(found) is not None:
        raise EndpointError(f"an agent is already running (127.0.0.1:{found.port})")
    server = socket.create_server(("127.0.0.1", 0))
    server.listen(16)
    endpoint = Endpoint(port=server.getsockname()[1], token=secrets.token_hex(16))
    written = base / (PORT_FILE + ".new")
    with contextlib.suppress(FileNotFoundError):
        written.unlink()
    fd = os.open(written, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as file:
        json.dump({"port": endpoint.port, "token": endpoint.token, "pid": os.getpid()}, file)
    os.replace(written, base / PORT_FILE)
    return server, endpoint


def forget(endpoint: Endpoint) -> None:
    """The agent stops: its socket or port file goes (if still its own)."""
    base = folder()
    with contextlib.suppress(OSError):
        if endpoint.path is not None:
            endpoint.path.unlink()
        else:
            found = _read_port_file(base / PORT_FILE)
            if found is not None and found.port == endpoint.port:
                (base / PORT_FILE).unlink()


def present() -> bool:
    """Whether an agent may be running (its socket or port file is there): checked
    before a front end loads what talking to one needs. No file is made."""
    try:
        runtime = os.environ.get("RAC_CONSOLE_AGENT_DIR") or _runtime_base()
        name = PORT_FILE if WINDOWS else SOCKET_NAME
        return (Path(runtime) / name).exists()
    except OSError:
        return False


def reach() -> tuple[socket.socket, Endpoint] | None:
    """A connection to the running agent, or None when there is none (no socket, or
    one left by an agent that died)."""
    try:
        base = folder()
    except OSError:
        return None
    if WINDOWS:
        found = _read_port_file(base / PORT_FILE)
        if found is None:
            return None
        sock = _reach_tcp(found)
        return None if sock is None else (sock, found)
    path = base / SOCKET_NAME
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.settimeout(CONNECT_TIMEOUT)
    try:
        sock.connect(str(path))
    except OSError:
        sock.close()
        return None
    sock.settimeout(None)  # a client waits on the agent as long as it runs
    from .wire import Channel

    if not Channel(sock).peer_is_us():  # a socket another user put there: no agent
        sock.close()
        return None
    return sock, Endpoint(path=path)


def _alive(path: Path) -> bool:
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
        probe.settimeout(CONNECT_TIMEOUT)
        try:
            probe.connect(str(path))
        except OSError:
            return False
    return True


def _read_port_file(path: Path) -> Endpoint | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return Endpoint(port=int(data["port"]), token=str(data["token"]))
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _reach_tcp(endpoint: Endpoint) -> socket.socket | None:
    try:
        sock = socket.create_connection(("127.0.0.1", endpoint.port or 0), CONNECT_TIMEOUT)
    except OSError:
        return None
    sock.settimeout(None)
    return sock
