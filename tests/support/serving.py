"""``rac-console serve`` as the tests drive it: the server and a simulator as
subprocesses (:class:`~tests.support.drivers.Running`), and plain HTTP and WebSocket
handshakes over a socket of the test's own, every read under a deadline.

- :func:`start_serve`: the server on 127.0.0.1 and a free port; its link, port, token;
- :func:`start_sim`: ``rac-console sim`` on a free port;
- :func:`request`: one HTTP/1.1 request, exactly the headers given (Host included);
- :func:`handshake`: a WebSocket opening handshake; :class:`Handshake` keeps the socket
  so that an accepted session stays open until closed;
- :func:`sim_value`: a variable as ``rac-console get --json`` reads it from outside;
- :func:`open_console`: the link spent and a session's socket opened, as a browser does.
"""

from __future__ import annotations

import base64
import codecs
import json
import os
import re
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

from tests.support.drivers import RAC, Running

#: How long a test waits for an answer, a line or a session: only a hang reaches it.
DEADLINE = 20.0


@dataclass
class Served:
    """A running ``rac-console serve``: its process and the link it printed."""

    running: Running
    url: str
    port: int
    token: str

    @property
    def origin(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    @property
    def host(self) -> str:
        return f"127.0.0.1:{self.port}"

    @property
    def cookie_name(self) -> str:
        return f"rac_console_{self.port}"


def start_serve(
    env: dict[str, str],
    running: list[Running],
    *args: str,
    before: tuple[str, ...] = (),
    cwd: Path | None = None,
    program: Sequence[str] = RAC,
    wrap: Sequence[str] = (),
    err_rate: int | None = None,
) -> Served:
    """``rac-console [BEFORE] serve --port 0 ARGS`` (in ``cwd``, as ``program``, its
    stderr read at ``err_rate`` bytes a second when given), once it printed its link."""
    run = Running(
        env,
        *before,
        "serve",
        "--port",
        "0",
        *args,
        cwd=cwd,
        program=program,
        wrap=wrap,
        err_rate=err_rate,
    )
    running.append(run)
    run.wait_for("the link", lambda: any(line.startswith("http://") for line in run.out))
    url = next(line for line in run.out if line.startswith("http://"))
    parts = urlsplit(url)
    assert parts.port is not None
    return Served(run, url, parts.port, parse_qs(parts.query)["token"][0])


def start_sim(env: dict[str, str], running: list[Running]) -> int:
    """``rac-console sim`` on a free port; its port."""
    run = Running(env, "sim", "--port", "0")
    running.append(run)
    found: list[int] = []

    def listening() -> bool:
        for line in run.out:
            if match := re.search(r"listening on 127\.0\.0\.1:(\d+)", line):
                found.append(int(match.group(1)))
                return True
        return False

    run.wait_for("the simulator", listening)
    return found[0]


def sim_value(env: dict[str, str], port: int, variable: str) -> object:
    """``rac-console get VARIABLE -H 127.0.0.1 -p PORT --json``: the value read."""
    where = ("-H", "127.0.0.1", "-p", str(port), "--json")
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "get", *variable.split(), *where],
        env=env,
        capture_output=True,
        text=True,
        timeout=DEADLINE,
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)["value"]


@dataclass
class Answer:
    """An HTTP answer: status, headers (names lowercased; Set-Cookie may repeat), body."""

    status: int
    headers: list[tuple[str, str]] = field(default_factory=list)
    body: bytes = b""

    def header(self, name: str) -> str | None:
        return next((v for k, v in self.headers if k == name.lower()), None)

    @property
    def text(self) -> str:
        return self.body.decode("utf-8", "replace")


def _read_head(sock: socket.socket) -> tuple[Answer, bytes]:
    data = b""
    deadline = time.monotonic() + DEADLINE
    while b"\r\n\r\n" not in data:
        sock.settimeout(max(0.01, deadline - time.monotonic()))
        chunk = sock.recv(65536)
        if not chunk:
            break
        data += chunk
    head, _, rest = data.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    status = int(lines[0].split()[1])
    headers = []
    for line in lines[1:]:
        name, _, value = line.partition(":")
        headers.append((name.strip().lower(), value.strip()))
    return Answer(status, headers), rest


def _send(port: int, path: str, headers: Mapping[str, str]) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=DEADLINE)
    lines = [f"GET {path} HTTP/1.1", *(f"{k}: {v}" for k, v in headers.items())]
    sock.sendall(("\r\n".join(lines) + "\r\n\r\n").encode("latin-1"))
    return sock


def request(port: int, path: str, headers: Mapping[str, str]) -> Answer:
    """``GET PATH`` with exactly ``headers`` (no Host unless given), the connection
    closed after it; the whole answer."""
    with _send(port, path, {**headers, "Connection": "close"}) as sock:
        answer, body = _read_head(sock)
        length = int(answer.header("content-length") or 0)
        deadline = time.monotonic() + DEADLINE
        while len(body) < length:
            sock.settimeout(max(0.01, deadline - time.monotonic()))
            chunk = sock.recv(65536)
            if not chunk:
                break
            body += chunk
    answer.body = body
    return answer


class Handshake:
    """A WebSocket opening handshake; the socket stays open (a 101 is a session)."""

    def __init__(self, port: int, headers: Mapping[str, str], path: str = "/ws") -> None:
        key = base64.b64encode(os.urandom(16)).decode()
        upgrade = {
            "Upgrade": "websocket",
            "Connection": "Upgrade",
            "Sec-WebSocket-Key": key,
            "Sec-WebSocket-Version": "13",
        }
        self.sock = _send(port, path, {**headers, **upgrade})
        self.answer, _ = _read_head(self.sock)

    @property
    def status(self) -> int:
        return self.answer.status

    def close(self) -> None:
        self.sock.close()


def handshake(port: int, headers: Mapping[str, str], path: str = "/ws") -> int:
    """The status of a WebSocket handshake, its socket closed at once."""
    made = Handshake(port, headers, path=path)
    made.close()
    return made.status


def cookie_of(answer: Answer, name: str) -> tuple[str, list[str]]:
    """The value of the cookie ``name`` an answer sets, and its attributes lowercased."""
    for key, value in answer.headers:
        if key == "set-cookie" and value.startswith(f"{name}="):
            first, *attributes = (part.strip() for part in value.split(";"))
            return first.partition("=")[2], [a.lower() for a in attributes]
    raise AssertionError(f"no cookie {name}: {answer.headers}")


def until(holds: Callable[[], bool], what: str, deadline: float = DEADLINE) -> None:
    """Ask ``holds`` every 50 ms until it holds; fail naming ``what`` after ``deadline``."""
    end = time.monotonic() + deadline
    while not holds():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {deadline} s waiting for {what}")
        time.sleep(0.05)


class Console:
    """One served session over a WebSocket of the test's own, as a browser drives it:
    textual-serve's messages (``["stdin", TEXT]``, ``["resize", ...]``) in masked text
    frames, the console's screen from the binary frames it sends back."""

    def __init__(self, port: int, path: str, headers: Mapping[str, str]) -> None:
        from tests.support.drivers import Screen

        self.made = Handshake(port, headers, path=path)
        self.sock = self.made.sock
        self.screen = Screen(1000)
        self._buffer = b""
        self.closed = False
        self.messages: list[object] = []  # the JSON messages (text frames) received
        self._decoder = codecs.getincrementaldecoder("utf-8")("replace")

    @property
    def status(self) -> int:
        return self.made.status

    def send(self, kind: str, data: object) -> None:
        payload = json.dumps([kind, data]).encode()
        mask = os.urandom(4)
        head = bytes([0x81])
        if len(payload) < 126:
            head += bytes([0x80 | len(payload)])
        elif len(payload) < 1 << 16:
            head += bytes([0x80 | 126]) + len(payload).to_bytes(2, "big")
        else:
            head += bytes([0x80 | 127]) + len(payload).to_bytes(8, "big")
        masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
        self.sock.sendall(head + mask + masked)

    def type_line(self, line: str) -> None:
        self.send("stdin", line + "\r")

    def _head(self) -> tuple[int, int] | None:
        """Where the next frame's payload starts and its length, once its head is in."""
        buffer = self._buffer
        if len(buffer) < 2:
            return None
        length = buffer[1] & 0x7F
        if length < 126:
            return 2, length
        size = 2 if length == 126 else 8
        if len(buffer) < 2 + size:
            return None
        return 2 + size, int.from_bytes(buffer[2 : 2 + size], "big")

    def _frame(self, deadline: float) -> tuple[int, bytes] | None:
        """The next frame the server sent (opcode, payload); None once it closed. A ping
        is answered, as a browser does (serve closes a socket that does not, in 15 s)."""
        while True:
            head = self._head()
            if head is not None and len(self._buffer) >= head[0] + head[1]:
                at, length = head
                opcode = self._buffer[0] & 0x0F
                payload = self._buffer[at : at + length]
                self._buffer = self._buffer[at + length :]
                if opcode == 0x9 and len(payload) < 126:
                    mask = os.urandom(4)
                    masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
                    self.sock.sendall(bytes([0x8A, 0x80 | len(payload)]) + mask + masked)
                    continue
                return opcode, payload
            self.sock.settimeout(max(0.01, deadline - time.monotonic()))
            chunk = self.sock.recv(65536)
            if not chunk:
                return None
            self._buffer += chunk

    def _read_one(self, end: float, waiting_for: object) -> None:
        """Read one frame and take it in: the screen, a JSON message, the close."""
        try:
            frame = self._frame(end)
        except TimeoutError:
            frame = None
        if frame is None or time.monotonic() > end:
            shown = "\n".join(self.screen.lines())
            raise AssertionError(f"timed out waiting for {waiting_for} on the console:\n{shown}")
        opcode, payload = frame
        if opcode == 0x2:
            self.screen.feed(self._decoder.decode(payload))
        elif opcode == 0x1:
            self.messages.append(json.loads(payload))
        elif opcode == 0x8:
            self.closed = True
            raise AssertionError(f"the session closed while waiting for {waiting_for}")

    def _until(self, shows: Callable[[str], bool], texts: tuple[str, ...], deadline: float) -> str:
        end = time.monotonic() + deadline
        while True:
            shown = "\n".join(self.screen.lines())
            if shows(shown):
                return shown
            self._read_one(end, texts)

    def until(self, *texts: str, deadline: float = DEADLINE) -> str:
        """Read frames until the screen shows every one of ``texts``; the screen."""
        return self._until(lambda shown: all(t in shown for t in texts), texts, deadline)

    def until_any(self, *texts: str, deadline: float = DEADLINE) -> str:
        """Read frames until the screen shows one of ``texts``; the screen."""
        return self._until(lambda shown: any(t in shown for t in texts), texts, deadline)

    def close_frame(self, deadline: float = DEADLINE) -> tuple[int, str]:
        """Read frames until the server closes the socket: its close code and reason."""
        end = time.monotonic() + deadline
        while True:
            try:
                frame = self._frame(end)
            except TimeoutError:
                frame = None
            if frame is None or time.monotonic() > end:
                raise AssertionError("the server did not close the socket")
            opcode, payload = frame
            if opcode == 0x8:
                self.closed = True
                code = int.from_bytes(payload[:2], "big") if len(payload) >= 2 else 1005
                return code, payload[2:].decode("utf-8", "replace")

    def until_message(self, wanted: Callable[[object], bool], deadline: float = DEADLINE) -> None:
        """Read frames until a JSON message that ``wanted`` holds for has come."""
        end = time.monotonic() + deadline
        while not any(wanted(message) for message in self.messages):
            self._read_one(end, "a message")

    def close(self) -> None:
        self.sock.close()


@dataclass(frozen=True)
class Login:
    """What the printed link buys a browser: the cookie, and the key the page opens
    the console's socket with (``/ws/KEY``)."""

    cookie: str
    key: str

    @property
    def socket(self) -> str:
        return f"/ws/{self.key}"


def spend_link(served: Served) -> Login:
    """The link opened as a browser would: the cookie it set and the key its redirect
    hands the page in the fragment (which no request carries)."""
    answer = request(served.port, f"/?token={served.token}", {"Host": served.host})
    assert answer.status == 303, answer.text
    location = answer.header("location") or ""
    assert location.startswith("/#key="), location
    return Login(cookie_of(answer, served.cookie_name)[0], location.partition("#key=")[2])


def open_console(served: Served, width: int = 120, height: int = 40) -> Console:
    """The link spent as a browser would, and the session's socket opened at that size."""
    login = spend_link(served)
    headers = {
        "Host": served.host,
        "Origin": served.origin,
        "Cookie": f"{served.cookie_name}={login.cookie}",
    }
    console = Console(served.port, f"{login.socket}?width={width}&height={height}", headers)
    assert console.status == 101, console.made.answer
    console.send("resize", {"width": width, "height": height})  # as the page does once open
    return console


def consoles_of(server_pid: int) -> list[int]:
    """The processes ``server_pid`` started that are still running (its sessions'
    consoles), read from /proc."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat.rpartition(")")[2].split()
        if fields and fields[0] != "Z" and int(fields[1]) == server_pid:
            found.append(int(entry.name))
    return found


def alive(pid: int) -> bool:
    """``pid`` runs (a zombie does not count)."""
    try:
        stat = (Path("/proc") / str(pid) / "stat").read_text()
    except OSError:
        return False
    return stat.rpartition(")")[2].split()[0] != "Z"
