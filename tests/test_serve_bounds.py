"""What one served session may send and cost (issue 42.1), judged from the machine's
side: the memory of the session's console process (/proc), its limits, the screen the
browser gets, the socket's close. Keys past a budget are dropped and said, a paste
goes whole, a message too big is dropped and said, the session stays open; the
console runs under a memory limit the OS enforces, and at it the session ends with a
line for the page, no traceback anywhere."""

from __future__ import annotations

import contextlib
import socket
from pathlib import Path

import pytest

from rac_console.present.served_bounds import KEYS_AT_ONCE, MESSAGE_MOST
from rac_console.serve.page import ENDED_CODE
from tests.support.serving import (
    DEADLINE,
    Console,
    Login,
    Served,
    alive,
    consoles_of,
    open_console,
    spend_link,
    start_serve,
    until,
)

pytest.importorskip("textual_serve", reason="needs the extra web")
pytestmark = pytest.mark.slow


def status_of(pid: int, name: str) -> int:
    """A ``kB`` figure of /proc/PID/status (VmRSS, VmData), in MB."""
    for line in (Path("/proc") / str(pid) / "status").read_text().splitlines():
        if line.startswith(f"{name}:"):
            return int(line.split()[1]) // 1024
    raise AssertionError(f"no {name} for {pid}")


def data_limit(pid: int) -> str:
    """The process's "Max data size" limit, soft and hard, as /proc/PID/limits says it."""
    for line in (Path("/proc") / str(pid) / "limits").read_text().splitlines():
        if line.startswith("Max data size"):
            return " ".join(line.split()[3:5])
    raise AssertionError(f"no data limit for {pid}")


def page(served: Served, login: Login) -> Console:
    """The session's socket as the page opens it (again, when it is reloaded)."""
    cookie = f"{served.cookie_name}={login.cookie}"
    headers = {"Host": served.host, "Origin": served.origin, "Cookie": cookie}
    console = Console(served.port, f"{login.socket}?width=120&height=40", headers)
    assert console.status == 101, console.made.answer
    return console


def download(served: Served, login: Login, key: str) -> bytes:
    """What ``/download/KEY`` answers, read to its end (it is sent in chunks)."""
    cookie = f"{served.cookie_name}={login.cookie}"
    asked = f"GET /download/{key} HTTP/1.1\r\nHost: {served.host}\r\nCookie: {cookie}\r\n"
    with socket.create_connection(("127.0.0.1", served.port), timeout=DEADLINE) as sock:
        sock.sendall(f"{asked}Connection: close\r\n\r\n".encode())
        answer = b"".join(iter(lambda: sock.recv(65536), b""))
    head, _, body = answer.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 200"), head
    chunks = b""
    while body and not body.startswith(b"0\r\n"):
        size, _, rest = body.partition(b"\r\n")
        chunks, body = chunks + rest[: int(size, 16)], rest[int(size, 16) + 2 :]
    return chunks


def the_console(served: Served) -> int:
    until(lambda: len(consoles_of(served.running.process.pid)) == 1, "the session's console")
    return consoles_of(served.running.process.pid)[0]


def test_32_kib_typed_as_keys_leave_the_console_small_and_a_get_answered(env, running) -> None:
    served = start_serve(env, running)
    console = open_console(served)
    console.until("SERVED", "connected")
    pid = the_console(served)
    for start in range(0, 32 * 1024, 8000):  # as the issue sent them
        console.send("stdin", "a" * min(8000, 32 * 1024 - start))
    with contextlib.suppress(AssertionError):  # the old console said nothing: typed on
        console.until("keys were dropped: a served console takes 1024 keys at once")
    for _ in range(20):  # typed again until taken, as a person would: a key that came
        console.send("stdin", "\x15")  # right behind the flood may be dropped with it
        console.type_line("get I 1")  # (Ctrl+U: the a's that were taken, gone)
        with contextlib.suppress(AssertionError):
            console.until("I1 = 1", deadline=1)
            break
    assert "I1 = 1" in "\n".join(console.screen.lines())  # it took up to two minutes
    assert status_of(pid, "VmRSS") < 250  # it was 705 MB


def test_a_paste_of_more_characters_than_keys_are_taken_goes_whole(env, running) -> None:
    served = start_serve(env, running)
    # Tall enough for every answer of the paste: its 31 lines run as fast as the
    # controller answers (not one a screen refresh), so on 40 rows the first line's
    # answer may have scrolled out of the results before the screen is first drawn.
    console = open_console(served, height=100)
    console.type_line("get I 1")
    console.until("I1 = ")  # the command line has the focus: a paste goes to it
    pasted = "get I 7" + " " * (KEYS_AT_ONCE - 16) + "\r" + "get I 8\r" * 30
    assert len(pasted) > KEYS_AT_ONCE
    console.send("stdin", "\x1b[200~" + pasted + "\x1b[201~")
    shown = console.until("I7 = ", "I8 = ")
    assert "dropped" not in shown


def test_a_message_past_its_size_is_dropped_and_said_and_the_session_goes_on(env, running) -> None:
    served = start_serve(env, running)
    console = open_console(served)
    console.type_line("get I 1")
    console.until("I1 = ")
    pasted = "\x1b[200~" + "get I 1\r" * (MESSAGE_MOST // 8) + "\x1b[201~"
    assert len(pasted) > MESSAGE_MOST
    console.send("stdin", pasted)
    console.until(f"{len(pasted):,} bytes the browser sent were dropped: a served console takes")
    console.type_line("get I 2")
    console.until("I2 = ")


def test_the_console_runs_under_the_memory_limit_serve_was_given(env, running) -> None:
    served = start_serve(env, running)
    open_console(served).until("SERVED", "connected")
    assert data_limit(the_console(served)) == f"{1024 << 20} {1024 << 20}"
    other = start_serve(env, running, "--session-memory", "300")
    open_console(other).until("SERVED", "connected")
    assert data_limit(the_console(other)) == f"{300 << 20} {300 << 20}"


def test_a_console_at_its_memory_limit_ends_and_its_page_is_told_why(env, running) -> None:
    served = start_serve(env, running, "--session-memory", "128")
    login = spend_link(served)
    console = page(served, login)
    console.until("SERVED", "connected")
    pid = the_console(served)
    assert status_of(pid, "VmData") < 115  # 90 % of the limit: where it is ended
    console.send("resize", {"width": 1000, "height": 1000})  # a big screen and a watch:
    console.type_line("watch T 0-255")  # it grows past its limit
    code, reason = console.close_frame(deadline=120)
    assert (code, reason) == (
        ENDED_CODE,
        "the console reached its memory limit of 128 MiB and ended "
        "(rac-console serve --session-memory)",
    )
    until(lambda: not alive(pid), "the console gone")
    assert status_of(served.running.process.pid, "VmRSS") > 0  # serve runs on
    again = page(served, login)  # the page reloaded: its slot came back
    again.until("SERVED", "connected")
    again.close()
    served.running.stop()
    said = "\n".join(served.running.out + served.running.err)
    assert "Traceback" not in said and "MemoryError" not in said


def test_screenshots_never_downloaded_are_not_kept_past_the_newest_three(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    console = page(served, login)
    console.until("SERVED", "connected")
    console.send("resize", {"width": 300, "height": 100})  # a screenshot of some size
    console.until("Frames")

    def delivered() -> list[str]:
        """The keys of the screenshots offered to the browser (never downloaded here)."""
        started = [m for m in console.messages if isinstance(m, list)]
        return [m[1] for m in started if m[0] == "deliver_file_start"]

    for taken in range(1, 6):
        console.send("stdin", "\x10")  # Ctrl+P: the palette
        console.until("Search for commands")
        console.send("stdin", "screenshot")
        console.until("Save an SVG")
        console.send("stdin", "\r")
        console.until_message(lambda _: len(delivered()) == taken)  # noqa: B023
    sizes = [len(download(served, login, key)) for key in delivered()]
    assert sizes[:2] == [0, 0] and min(sizes[2:]) > 100_000, sizes  # the oldest two: gone
