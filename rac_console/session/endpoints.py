"""Which addresses a host stands for: so a profile's rules follow its controller however
its address is typed (``127.1``, ``localhost``, ``0x7f000001``, a DNS name or the IP).

Names are resolved as the session will resolve them when it connects (``getaddrinfo``),
each at most once per process, on a thread with a deadline: a DNS server that does not
answer must not hold the console's start for longer than :data:`RESOLVE_SECONDS`.
"""

from __future__ import annotations

import ipaddress
import socket
import threading
from concurrent.futures import Future

#: How long one name may take to resolve before it counts as unresolvable.
RESOLVE_SECONDS = 3.0

_lock = threading.Lock()
_cache: dict[str, Future[frozenset[str] | None]] = {}


def addresses(host: str) -> frozenset[str] | None:
    """The addresses ``host`` resolves to, IPv4-mapped IPv6 ones as IPv4; None when it
    cannot be resolved (no such name, no answer within :data:`RESOLVE_SECONDS`)."""
    key = host.casefold()
    with _lock:
        future = _cache.get(key)
        if future is None:
            future = _cache[key] = Future()
            threading.Thread(
                target=_resolve, args=(host, future), name="rac-resolve", daemon=True
            ).start()
    try:
        return future.result(RESOLVE_SECONDS)
    except TimeoutError:
        return None


def _resolve(host: str, future: Future[frozenset[str] | None]) -> None:
    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError, ValueError):
        future.set_result(None)
        return
    found: set[str] = set()
    for *_, sockaddr in infos:
        try:
            ip = ipaddress.ip_address(str(sockaddr[0]).split("%", 1)[0])
        except ValueError:
            continue
        if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is not None:
            ip = ip.ipv4_mapped
        found.add(str(ip))
    future.set_result(frozenset(found) or None)
