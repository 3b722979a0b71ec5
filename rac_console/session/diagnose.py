"""The probe behind ``rac-console check``: each step between here and a controller, tried
in order over real sockets, stopping at the first that fails.

Name resolution, a TCP connection, a GET answered, a few more GETs timed, then a second
session opened while the first stays open (the RAC spec recommends several sessions for
several requests in flight; a controller that takes only one locks every other client
out while one holds it). Only GETs are sent: nothing is ever written. Connections go
through :class:`Session`, so the check sees what the console would see (its timeouts,
its reply checks); the words for each failure live in :mod:`rac_console.commands.check`.
"""

from __future__ import annotations

import ipaddress
import socket
import statistics
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future

from ..commands.check import CheckReport, Problem, StepName, StepResult
from ..protocol import describe_hresult, kind_of
from ..protocol.request import get_for
from ..protocol.text import endpoint, escape_bytes
from .blocking import Session
from .endpoints import RESOLVE_SECONDS
from .sockets import reason_of
from .types import (
    BadReply,
    ConnectFailed,
    Disconnected,
    FrameObserver,
    Reply,
    RequestTimeout,
    State,
    TransportError,
)

#: The GET every step sends: I0 exists on every RC8, and reading it changes nothing.
PROBE = get_for(kind_of("I"), 0)

#: GETs timed for the round trip.
ROUND_TRIPS = 5

#: getaddrinfo's "try again": the name server did not answer (glibc, WSATRY_AGAIN).
_NAME_SERVER_BUSY = {socket.EAI_AGAIN, 11002}

#: How the second session's failures start.
SECOND = "a second connection, opened with the first still open"

#: A median round trip over this (seconds) is said to be slow for a cable.
SLOW = 0.05


class _StepFailed(Exception):
    """A step failed: its result says how, and the check stops there."""

    def __init__(self, result: StepResult) -> None:
        super().__init__(result.detail)
        self.result = result


class _Link:
    """A session, and how often its connection was closed under it: the session opens a
    new one by itself, which the console wants and a check must not hide."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.closed = 0
        session.add_state_observer(self._on_state)

    def _on_state(self, state: State) -> None:
        if state == "closed":
            self.closed += 1


def diagnose(
    host: str,
    port: int,
    *,
    timeout: float,
    observers: Sequence[FrameObserver] = (),
    resolve_within: float = RESOLVE_SECONDS,
    round_trips: int = ROUND_TRIPS,
) -> CheckReport:
    """Try each step against ``host:port`` and say how each went. Every wait is bounded:
    ``resolve_within`` for the name, ``timeout`` for each connect and each reply.
    ``observers`` see every frame of both sessions (``--record``, ``--log``)."""
    done: list[StepResult] = []
    links: list[_Link] = []

    def link_to(address: str) -> _Link:
        session = Session(address, port, timeout=timeout)
        for observer in observers:
            session.add_frame_observer(observer)
        links.append(_Link(session))
        return links[-1]

    try:
        addresses = _resolve(host, resolve_within, done)
        first = _connect(addresses, port, link_to, done)
        _first_get(first, done)
        _round_trip(first, round_trips, done)
        _second_session(first, link_to, done)
    except _StepFailed as failed:
        done.append(failed.result)
    finally:
        for link in links:
            link.session.close()  # a controller with one session is free for others at once
    return CheckReport.of(host, port, done, timeout)


# ----------------------------------------------------------------- the steps


def _resolve(host: str, within: float, done: list[StepResult]) -> list[str]:
    """The addresses ``host`` stands for, in the order a connection tries them."""
    started = time.perf_counter()
    future: Future[list[str]] = Future()
    # getaddrinfo has no timeout of its own: a name server that never answers would hold
    # the check for as long as the resolver's retries last, so it runs on a thread.
    threading.Thread(
        target=_getaddrinfo, args=(host, future), name="rac-check-resolve", daemon=True
    ).start()
    try:
        found = future.result(within)
    except TimeoutError:
        detail = f"{host}: no answer from the name server within {within:g} s"
        raise _failed("resolve", started, detail, "dns timeout") from None
    except (OSError, UnicodeError, ValueError) as exc:
        busy = isinstance(exc, socket.gaierror) and exc.errno in _NAME_SERVER_BUSY
        problem: Problem = "dns timeout" if busy else "unknown host"
        raise _failed("resolve", started, f"{host}: {reason_of(exc)}", problem) from None
    seconds = time.perf_counter() - started
    if _is_address(host):
        detail = f"{host} is an IP address: nothing to look up"
    else:
        shown = ", ".join(found[:3]) + (f" and {len(found) - 3} more" if len(found) > 3 else "")
        detail = f"{host} is {shown} ({seconds * 1000:.1f} ms)"
    done.append(StepResult("resolve", True, seconds, detail))
    return found


def _connect(
    addresses: list[str], port: int, link_to: Callable[[str], _Link], done: list[StepResult]
) -> _Link:
    """A TCP connection to the first address that takes one, as the session makes it."""
    started = time.perf_counter()
    failures: list[tuple[str, Problem]] = []
    for address in addresses:
        link = link_to(address)
        tried = time.perf_counter()
        try:
            link.session.connect()
        except ConnectFailed as exc:
            failures.append((str(exc), exc.problem))
            continue
        except Disconnected as exc:  # taken, then closed at once
            failures.append((f"{endpoint(address, port)}: {exc}", "closed"))
            continue
        link.closed = 0
        seconds = time.perf_counter() - tried
        detail = f"TCP connection to {endpoint(address, port)} in {seconds * 1000:.1f} ms"
        done.append(StepResult("connect", True, seconds, detail))
        return link
    detail = "; ".join(text for text, _ in failures) or "no address to connect to"
    raise _failed("connect", started, detail, failures[0][1] if failures else "failed")


def _first_get(link: _Link, done: list[StepResult]) -> None:
    """One GET answered: RAC itself, not only something listening on the port."""
    started = time.perf_counter()
    reply = _get(link, "get", f"the GET ({PROBE.text})", started)
    detail = f"{PROBE.text} answered {escape_bytes(reply.raw)} in {reply.rtt * 1000:.2f} ms"
    done.append(StepResult("get", True, reply.rtt, detail))


def _round_trip(link: _Link, count: int, done: list[StepResult]) -> None:
    """A few GETs in a row: how long a request takes, typically and at worst."""
    started = time.perf_counter()
    rtts = [
        _get(link, "round_trip", f"GET {n} of {count}", started).rtt for n in range(1, count + 1)
    ]
    median = statistics.median(rtts)
    detail = f"{count} GETs: median {median * 1000:.2f} ms, max {max(rtts) * 1000:.2f} ms"
    if median > SLOW:
        detail += " (slow for a cable: a busy controller or network)"
    done.append(StepResult("round_trip", True, time.perf_counter() - started, detail))


def _second_session(first: _Link, link_to: Callable[[str], _Link], done: list[StepResult]) -> None:
    """A second connection, opened while the first stays open, answers a GET; and the
    first still answers after it (a controller may push the older session out)."""
    started = time.perf_counter()
    second = link_to(first.session.host)
    try:
        second.session.connect()
    except ConnectFailed as exc:
        raise _failed("second_session", started, f"{SECOND}: {exc}", exc.problem) from None
    except Disconnected as exc:
        raise _failed("second_session", started, f"{SECOND}: {exc}", "closed") from None
    second.closed = 0
    _get(second, "second_session", SECOND, started)
    _get(
        first,
        "second_session",
        "the first connection, after the second opened",
        started,
        "displaced",
    )
    detail = (
        "a second connection answered a GET while the first stayed open, and the first "
        "still answers"
    )
    done.append(StepResult("second_session", True, time.perf_counter() - started, detail))


# ----------------------------------------------------------------- helpers


def _failed(step: StepName, started: float, detail: str, problem: Problem) -> _StepFailed:
    return _StepFailed(StepResult(step, False, time.perf_counter() - started, detail, problem))


def _get(
    link: _Link, step: StepName, what: str, started: float, closed: Problem = "closed"
) -> Reply:
    """One GET of I0, answered S_OK on the connection it was sent on; else the step
    fails, saying how (``closed``: what a connection closed under it means here)."""
    problem: Problem
    before = link.closed
    try:
        reply = link.session.exchange(PROBE)
    except RequestTimeout as exc:
        text, problem = str(exc), "no answer"
    except BadReply as exc:
        text, problem = str(exc), "bad reply"
    except Disconnected as exc:
        text, problem = str(exc), closed
    except ConnectFailed as exc:  # its connection closed, and a new one could not be made
        text, problem = f"the controller closed it, and {exc}", closed
    except TransportError as exc:
        text, problem = str(exc), "failed"
    else:
        if link.closed != before:
            text = "the controller had closed it (the GET went out again on a new connection)"
            problem = closed
        elif reply.response.ok:
            return reply
        else:
            text = f"answered {escape_bytes(reply.raw)}: {describe_hresult(reply.response.code)}"
            problem = "error"
    raise _failed(step, started, f"{what}: {text}", problem)


def _getaddrinfo(host: str, future: Future[list[str]]) -> None:
    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
    except BaseException as exc:  # handed to the caller, who words it
        future.set_exception(exc)
        return
    found: list[str] = []
    for *_, sockaddr in infos:
        address = str(sockaddr[0])
        if address not in found:
            found.append(address)
    future.set_result(found)


def _is_address(host: str) -> bool:
    try:
        ipaddress.ip_address(host.split("%", 1)[0])
    except ValueError:
        return False
    return True
