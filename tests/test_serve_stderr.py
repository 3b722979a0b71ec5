"""``rac-console serve``'s own standard error cannot be made to flood it or to stall it:
one line per kind of refusal every 10 s with a count, no traceback for a request it
could not read, and a terminal that does not read holds no request up (the operator's
``get`` is answered while stderr is read at 200 bytes a second under a flood). Also:
a console that quit is reaped once (no "Unknown child process pid")."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import re
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rac_console.serve.said import Said, Tally
from tests.support.serving import DEADLINE, Served, open_console, start_serve, until

pytest.importorskip("textual_serve", reason="needs the extra web")

#: Requests every kind of which serve refuses, as raw bytes (HOST and PORT filled in).
REFUSED = {
    "no cookie": b"GET / HTTP/1.1\r\nHost: HOST\r\nConnection: close\r\n\r\n",
    "foreign host": b"GET / HTTP/1.1\r\nHost: evil.example:PORT\r\nConnection: close\r\n\r\n",
    "malformed": b"GET / HTTP/1.1\r\nHost: HOST\r\nContent-Length: x\r\n\r\n",
    "bad header": b"GET / HTTP/1.1\r\nHo st: x\r\nHost: HOST\r\n\r\n",
}


def send_raw(served: Served, raw: bytes) -> bytes:
    """``raw`` sent on a connection of its own; what came back until it closed."""
    data = raw.replace(b"HOST", served.host.encode()).replace(b"PORT", str(served.port).encode())
    with socket.create_connection(("127.0.0.1", served.port), timeout=DEADLINE) as sock:
        sock.sendall(data)
        answer = b""
        while chunk := sock.recv(65536):
            answer += chunk
    return answer


@pytest.fixture
def flood() -> Iterator[Callable[[Served, int], None]]:
    """Threads sending refused requests of every kind, back to back, until the test ends."""
    stop = threading.Event()
    threads: list[threading.Thread] = []

    def start(served: Served, count: int) -> None:
        def loop(raw: bytes) -> None:
            while not stop.is_set():
                with contextlib.suppress(OSError):
                    send_raw(served, raw)

        for n in range(count):
            raw = list(REFUSED.values())[n % len(REFUSED)]
            threads.append(threading.Thread(target=loop, args=(raw,), daemon=True))
            threads[-1].start()

    yield start
    stop.set()
    for thread in threads:
        thread.join(DEADLINE)


@pytest.mark.slow
def test_a_flood_of_refusals_with_a_stalled_stderr_does_not_stall_the_operator(
    env, running, flood
) -> None:
    """stderr read at 200 bytes a second (a terminal or ssh link that does not keep up)
    while 8 clients send refused requests back to back: the operator's get is answered.
    Before, each refusal's line was written by the event loop itself, which waited on the
    pipe: the get went unanswered for more than 30 s."""
    served = start_serve(env, running, err_rate=200)
    console = open_console(served)
    try:
        console.until("connected")
        flood(served, 8)
        until(lambda: len(served.running.err) >= 2, "the refusals said on stderr")
        console.type_line("get I 1")
        console.until("I1 = 1", deadline=DEADLINE)
    finally:
        console.close()


@pytest.mark.slow
def test_refusals_are_one_line_a_kind_with_a_count_and_no_traceback(env, running) -> None:
    """100 requests of each refused kind, then serve stopped: a few lines, each kind's
    first and then one with the count of the rest; no traceback, nothing dropped."""
    served = start_serve(env, running)
    for _ in range(100):
        for raw in REFUSED.values():
            assert send_raw(served, raw).split(b" ", 2)[1] in (b"400", b"403", b"421")
    assert served.running.stop() == 0
    err = served.running.err
    assert not any("Traceback" in line or line.startswith("  ") for line in err), err
    assert len(err) <= 3 * 2 * 2, err  # 3 kinds (two malformed requests are one): a first
    # line and one with the count, twice at most on a slow machine (a window is 10 s)
    counted = 0
    for line in err:
        assert line.startswith("rac-console serve: refused "), line
        more = re.search(r" … and ([\d,]+) more in the last \d+ s$", line)
        counted += 1 + (int(more.group(1).replace(",", "")) if more else 0)
    assert counted == 400, err  # every refusal counted, none lost
    assert any(
        "a malformed request: 400, Invalid character in Content-Length" in line for line in err
    )


def test_the_tally_says_the_first_of_a_kind_and_counts_the_rest() -> None:
    tally = Tally(window=10)
    assert tally.say("403", "a", now=0) == "a"
    assert tally.say("421", "x", now=1) == "x"  # another kind: said too
    assert tally.say("403", "b", now=2) is None
    assert tally.say("403", "c", now=9) is None
    assert tally.due(now=9.9) == []
    assert tally.due(now=10) == ["c … and 1 more in the last 10 s"]
    assert tally.due(now=11) == []  # 421's window closed quiet: its next line is said at once
    assert tally.say("421", "y", now=11) == "y"
    assert tally.say("403", "d", now=12) is None  # 403's new window runs from 10
    assert tally.due(now=20) == ["d"]  # one held: said as it is
    assert tally.due(now=30) == []
    assert tally.say("403", "e", now=31) == "e"
    for n in range(1234):
        tally.say("403", f"f{n}", now=32)
    assert tally.due(now=35, closing=True) == ["f1233 … and 1,233 more in the last 4 s"]


def test_a_terminal_that_does_not_read_loses_lines_counted_not_the_server() -> None:
    """The writing thread is stuck (the terminal does not read): saying never waits, what
    does not fit is dropped, and the count is said once the terminal reads again."""
    written: list[bytes] = []
    reading = threading.Event()

    def write(data: bytes) -> None:
        reading.wait(DEADLINE)
        written.append(data)

    said = Said(write, window=1000, most_waiting=500)
    start = time.monotonic()
    for n in range(2000):
        said.say(f"kind {n}", f"line {n} " + "x" * 40)
    assert time.monotonic() - start < DEADLINE  # never waited on the stuck write
    reading.set()
    said.close(wait=DEADLINE)
    text = b"".join(written).decode()
    lines = text.splitlines()
    assert 5 < len(lines) < 20, lines
    assert re.search(
        r"rac-console serve: [\d,]+ lines not shown: this standard error was not read", text
    )


@pytest.mark.slow
async def test_a_console_that_quit_is_reaped_by_asyncio_alone(monkeypatch, caplog) -> None:
    """A console that has just quit, not yet reaped by asyncio's child watcher (held
    back here): stopping its service does not reap it behind the watcher's back, which
    then said "Unknown child process pid" on serve's stderr and reported it as 255."""
    from textual_serve.download_manager import DownloadManager

    from rac_console.serve.textual_serve_parts import ExecAppService

    real_waitpid = os.waitpid

    def slow_waitpid(pid: int, options: int) -> tuple[int, int]:
        if options == 0:  # the watcher's: blocking
            time.sleep(0.5)
        return real_waitpid(pid, options)

    monkeypatch.setattr(os, "waitpid", slow_waitpid)

    async def nothing(*_: object) -> None:
        return None

    service = ExecAppService(
        [sys.executable, "-c", "pass"],
        {},
        write_bytes=nothing,
        write_str=nothing,
        close=nothing,
        download_manager=DownloadManager(),
        debug=False,
    )
    process = await service._open_app_process()
    stat = Path(f"/proc/{process.pid}/stat")
    end = time.monotonic() + DEADLINE
    while stat.read_text().rpartition(")")[2].split()[0] != "Z":  # the loop held: no reaping
        assert time.monotonic() < end, "the console never ended"
        time.sleep(0.01)
    with caplog.at_level(logging.WARNING, logger="asyncio"):
        await service.end()
        await asyncio.wait_for(process.wait(), DEADLINE)  # the held-back watcher's word
    assert process.returncode == 0
    assert not [r for r in caplog.records if "Unknown child process" in r.getMessage()]


def test_what_a_request_carries_is_escaped_on_stderr() -> None:
    written: list[bytes] = []
    said = Said(written.append)
    said.say("421 host", "refused GET / from 127.0.0.1: 421 (Host 'ev\x1b[2Jil')")
    said.close(wait=DEADLINE)
    assert b"".join(written) == (
        b"rac-console serve: refused GET / from 127.0.0.1: 421 (Host 'ev\\x1b[2Jil')\n"
    )


@pytest.mark.slow
def test_out_of_file_descriptors_is_one_line_not_a_traceback_a_connection(env, running) -> None:
    """serve under ``ulimit -n 64`` and 150 connections held: the accepts that fail
    (Too many open files) are one line with a count, not a traceback each (before,
    2,000 held connections at 1024 printed 26k tracebacks in 75 s)."""
    served = start_serve(env, running, wrap=("sh", "-c", 'ulimit -n 64 && exec "$0" "$@"'))
    held: list[socket.socket] = []
    try:
        for _ in range(150):
            with contextlib.suppress(OSError):  # the kernel's backlog full: enough
                held.append(socket.create_connection(("127.0.0.1", served.port), timeout=1))
        until(
            lambda: any("Too many open files" in line for line in served.running.err),
            "the accept's failure said",
        )
    finally:
        for sock in held:
            sock.close()
    assert served.running.stop() == 0
    err = served.running.err
    assert not any("Traceback" in line for line in err), err[:20]
    failed = [line for line in err if "Too many open files" in line]
    assert failed[0] == (
        "rac-console serve: cannot accept a connection: Too many open files (tried again in 1 s)"
    )
    assert len(failed) <= 3, err  # the first, and a count a 10 s (and one at the stop)
