"""Run parsed commands over a session and turn every result into an Outcome.

The one place where a command meets the client, shared by the CLI, ``run``,
the REPL and the console.
"""

from __future__ import annotations

import asyncio
import time

from .client import (
    PRIORITY_COMMAND,
    BadReply,
    ConnectFailed,
    RacSession,
    RequestTimeout,
    TransportError,
)
from .commands.language import Exchange, Get, Put, Raw, VarRef
from .commands.latency import LatencySummary, summarize
from .commands.outcome import ExitStatus, Outcome, refused
from .protocol import InputError, describe_hresult, escape_bytes
from .protocol.messages import is_well_formed_get


def is_write(command: Exchange) -> bool:
    """True for a typed or raw PUT: a timeout then leaves its outcome unknown."""
    if isinstance(command, Put):
        return True
    return isinstance(command, Raw) and command.wire.lstrip(" \t")[:3].upper() == "PUT"


def read_only_refusal(command: Exchange) -> str | None:
    """Why read-only keeps this off the wire; None for a well-formed GET, the only
    thing read-only lets out (in every front end, and for raw lines alike)."""
    if is_well_formed_get(command.wire):
        return None
    if is_write(command):
        return "PUT refused: read-only mode is on (nothing was sent)"
    return (
        "refused: read-only mode sends only well-formed GET requests "
        "(GET:RC8:<index>:<type>:, e.g. GET:RC8:10:I:); nothing was sent"
    )


async def execute(
    session: RacSession,
    command: Exchange,
    *,
    read_only: bool = False,
    line: str | None = None,
    priority: int = PRIORITY_COMMAND,
) -> Outcome:
    """Send one command and describe what came of it; never raises for I/O."""
    wire = command.wire
    var = command.var if isinstance(command, (Get, Put)) else None
    if read_only and (refusal := read_only_refusal(command)) is not None:
        return refused(line, refusal, wire)
    try:
        if isinstance(command, Get):
            reply = await session.get(command.var.kind, command.var.index, priority=priority)
        elif isinstance(command, Put):
            reply = await session.put(command.var.kind, command.var.index, command.value)
        else:
            reply = await session.send_raw(wire)
    except InputError as exc:
        return refused(line, str(exc), wire)
    except RequestTimeout as exc:
        message = str(exc)
        if is_write(command):
            message += ": outcome unknown, the PUT may have been applied"
        return Outcome(wire, ExitStatus.TRANSPORT, var, error=message, input_line=line, failure=exc)
    except TransportError as exc:
        text = escape_bytes(exc.raw) if isinstance(exc, BadReply) and exc.raw is not None else None
        return Outcome(
            wire,
            ExitStatus.TRANSPORT,
            var,
            response_text=text,
            error=str(exc),
            input_line=line,
            failure=exc,
        )
    response = reply.response
    status = ExitStatus.OK if response.ok else ExitStatus.CONTROLLER_ERROR
    return Outcome(
        wire,
        status,
        var,
        reply.text,
        response,
        reply.rtt,
        error=None if response.ok else f"controller answered {describe_hresult(response.code)}",
        input_line=line,
        written=command.value if isinstance(command, Put) else None,
    )


async def measure_latency(
    session: RacSession, var: VarRef, count: int, interval: float
) -> LatencySummary:
    """GET one variable ``count`` times, ``interval`` seconds apart (0: back to back).

    Raises ConnectFailed when the controller cannot be reached at all.
    """
    samples: list[float] = []
    errors = 0
    started = time.perf_counter()
    for n in range(count):
        if n and interval:
            await asyncio.sleep(interval)
        try:
            reply = await session.get(var.kind, var.index)
        except ConnectFailed:
            raise
        except TransportError:
            errors += 1
            continue
        if reply.response.ok:
            samples.append(reply.rtt)
        else:
            errors += 1
    return summarize(samples, errors, time.perf_counter() - started)
