"""Clients that misbehave, shared by ``benchmarks/sim_abuse.py`` (full counts, figures)
and ``tests/test_sim_abuse.py`` (small counts, assertions).

Every one talks only to 127.0.0.1, is bounded in time, and closes what it opened.
"""

from __future__ import annotations

import contextlib
import os
import socket
import time

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
