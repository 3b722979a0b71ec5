"""What the session does to its socket below the protocol: the options a connection is
opened with (no Nagle delay, keepalive, the timeouts in the kernel), asking it without
blocking whether the peer spoke, ended it or left bytes waiting, resetting or closing
it; and the words for why a connection failed, the same on Linux, macOS and Windows.

:class:`~.blocking.Session` owns the socket and the protocol's state; these functions
hold no state of their own. ``rac-console check`` (:mod:`.diagnose`) words its failures
with :func:`reason_of` too.
"""

from __future__ import annotations

import contextlib
import errno
import os
import select
import socket
import struct
import sys
from typing import Any

from .types import MAX_REPLY_LINE, ConnectProblem

READ_SIZE = 65536

#: TCP keepalive: an idle connection is probed after KEEPALIVE_IDLE seconds of silence,
#: every KEEPALIVE_INTERVAL seconds, and given up after KEEPALIVE_COUNT unanswered
#: probes: a controller that vanished (rebooted while the cable was out) is known dead
#: about 11 s into a quiet spell, not at the next command.
KEEPALIVE_IDLE = 5
KEEPALIVE_INTERVAL = 2
KEEPALIVE_COUNT = 3


def prepare(sock: socket.socket, timeout: float) -> bool:
    """A connection just made, readied for the session: no Nagle delay, keepalive, and
    ``timeout`` on each send and read, in the kernel where it can be (True) or as
    Python's socket timeout (False)."""
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    set_keepalive(sock)
    in_kernel = set_kernel_timeout(sock, timeout)
    sock.settimeout(None if in_kernel else timeout)
    return in_kernel


def set_timeout(sock: socket.socket, seconds: float, in_kernel: bool) -> None:
    """Each later send and read waits at most ``seconds`` (``in_kernel``: as
    :func:`prepare` set it)."""
    if not (in_kernel and set_kernel_timeout(sock, seconds)):
        sock.settimeout(seconds)


def set_kernel_timeout(sock: socket.socket, seconds: float) -> bool:
    """Put the send and receive timeouts in the kernel (SO_SNDTIMEO, SO_RCVTIMEO), so a
    blocking ``recv`` is one system call instead of Python's poll-then-recv. False where
    the options cannot be set: the caller then uses Python's socket timeout."""
    try:
        if sys.platform == "win32":
            value = struct.pack("=L", max(1, round(seconds * 1000)))  # a DWORD of ms
        else:
            whole = int(seconds)
            value = struct.pack("@ll", whole, max(1, int((seconds - whole) * 1e6)))
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, value)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDTIMEO, value)
    except (OSError, AttributeError, struct.error, OverflowError):
        return False
    return True


def set_keepalive(sock: socket.socket) -> None:
    """TCP keepalive with an idle time of seconds (the systems' default is two hours),
    on Linux, macOS and Windows; left at the system's where an option is missing."""
    with contextlib.suppress(OSError, AttributeError, ValueError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
        if sys.platform == "win32":
            ms = (1, KEEPALIVE_IDLE * 1000, KEEPALIVE_INTERVAL * 1000)
            sock.ioctl(socket.SIO_KEEPALIVE_VALS, ms)  # type: ignore[attr-defined]
            return
        idle = getattr(socket, "TCP_KEEPIDLE", None) or getattr(socket, "TCP_KEEPALIVE", None)
        for option, value in (
            (idle, KEEPALIVE_IDLE),
            (getattr(socket, "TCP_KEEPINTVL", None), KEEPALIVE_INTERVAL),
            (getattr(socket, "TCP_KEEPCNT", None), KEEPALIVE_COUNT),
        ):
            if option is not None:
                sock.setsockopt(socket.IPPROTO_TCP, option, value)


def readable(sock: socket.socket, timeout: float = 0.0, poll: Any = None) -> bool:
    """True when bytes, EOF or an error wait on ``sock``, after waiting up to
    ``timeout`` seconds for them; asked through ``poll`` (registered for ``sock``, never
    waiting) when given, else ``select``. A socket that cannot be asked cannot be
    trusted: True."""
    try:
        if poll is not None:
            return bool(poll.poll(0))
        return bool(select.select((sock,), (), (), timeout)[0])
    except (OSError, ValueError):
        return True


def ended(sock: socket.socket) -> str | None:
    """Why the peer ended the connection (EOF, an error), seen without taking a byte;
    None while it is open (nothing waits, or bytes do)."""
    timeout = sock.gettimeout()
    try:
        sock.setblocking(False)
        try:
            if sock.recv(1, socket.MSG_PEEK):
                return None
            return "the controller closed the connection"
        finally:
            sock.settimeout(timeout)
    except BlockingIOError:
        return None
    except OSError as exc:
        return f"the connection failed: {reason_of(exc)}"


def read_waiting(sock: socket.socket) -> tuple[bytes, bool]:
    """What waits on ``sock``, read without blocking for the log, and whether the
    connection is still open (the read stopped for want of bytes, not at EOF or error)."""
    chunks: list[bytes] = []
    limit = MAX_REPLY_LINE
    still_open = False
    timeout = sock.gettimeout()
    try:
        sock.setblocking(False)
        size = 0
        while size < limit:
            chunk = sock.recv(min(READ_SIZE, limit - size))
            if not chunk:
                break  # EOF
            chunks.append(chunk)
            size += len(chunk)
    except BlockingIOError:
        still_open = True  # all read
    except OSError:
        pass  # reset: drop it all the same
    finally:
        with contextlib.suppress(OSError):
            sock.settimeout(timeout)
    return b"".join(chunks), still_open


def close(sock: socket.socket, abort: bool = False) -> None:
    """Close ``sock``; with ``abort``, reset it (SO_LINGER on, time 0), so what it still
    holds unsent is discarded rather than delivered."""
    if abort:
        layout = "=HH" if sys.platform == "win32" else "ii"
        with contextlib.suppress(OSError, struct.error):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack(layout, 1, 0))
    with contextlib.suppress(OSError):
        sock.close()


def shut(sock: socket.socket) -> None:
    """Shut both ways: a read or send blocked on ``sock`` in another thread ends."""
    with contextlib.suppress(OSError):
        sock.shutdown(socket.SHUT_RDWR)


#: errno values (POSIX and WinSock) of a host or network that cannot be reached.
_UNREACHABLE = {
    getattr(errno, "EHOSTUNREACH", 113),
    getattr(errno, "ENETUNREACH", 101),
    getattr(errno, "EHOSTDOWN", 112),
    getattr(errno, "ENETDOWN", 100),
    10065,  # WSAEHOSTUNREACH
    10051,  # WSAENETUNREACH
    10064,  # WSAEHOSTDOWN
    10050,  # WSAENETDOWN
}


def problem_of(exc: BaseException) -> ConnectProblem:
    """Why a connection could not be opened, in a word, the same on every system."""
    if isinstance(exc, socket.gaierror | UnicodeError | ValueError):
        return "unknown host"
    if isinstance(exc, ConnectionRefusedError):
        return "refused"
    if isinstance(exc, TimeoutError):
        return "timed out"
    if isinstance(exc, OSError) and (
        exc.errno in _UNREACHABLE or getattr(exc, "winerror", None) in _UNREACHABLE
    ):
        return "unreachable"
    return "failed"


#: The words for the failures a user can act on, keyed by errno and WinSock code, so
#: Linux, macOS and Windows say them alike: os.strerror knows no WinSock code (it says
#: "Unknown error" for 10061), and each system words its own codes its own way.
_WORDS = {
    errno.ECONNREFUSED: "Connection refused",
    10061: "Connection refused",  # WSAECONNREFUSED
    errno.ETIMEDOUT: "timed out",
    10060: "timed out",  # WSAETIMEDOUT
    errno.EHOSTUNREACH: "No route to host",
    10065: "No route to host",  # WSAEHOSTUNREACH
    errno.ENETUNREACH: "Network is unreachable",
    10051: "Network is unreachable",  # WSAENETUNREACH
}

#: getaddrinfo's codes for a name that does not exist: glibc and macOS (EAI_NONAME,
#: EAI_NODATA) and WinSock (WSAHOST_NOT_FOUND 11001, WSANO_DATA 11004). They are a
#: table of their own: macOS's EAI_NONAME is 8, an errno too.
_NAME_NOT_FOUND = {
    socket.EAI_NONAME,
    getattr(socket, "EAI_NODATA", socket.EAI_NONAME),
    11001,  # WSAHOST_NOT_FOUND
    11004,  # WSANO_DATA
}


def reason_of(exc: BaseException) -> str:
    """Why a connection failed, in words: never 'Unknown error -2', nor Windows'
    'Unknown error' for a WinSock code (a table first, then the exception's own text)."""
    if isinstance(exc, TimeoutError):
        return "timed out"
    if isinstance(exc, socket.gaierror):
        if exc.errno in _NAME_NOT_FOUND:
            return "host not found"
        if exc.strerror:
            return exc.strerror  # "Temporary failure in name resolution"
    elif isinstance(exc, OSError):
        for code in (getattr(exc, "winerror", None), exc.errno):
            if code in _WORDS:
                return _WORDS[code]
        if exc.strerror:
            return exc.strerror  # the system's own words for this exception
        if exc.errno and exc.errno > 0:
            return os.strerror(exc.errno)
    if isinstance(exc, UnicodeError | ValueError):
        return "not a valid host name"
    return str(exc) or type(exc).__name__
