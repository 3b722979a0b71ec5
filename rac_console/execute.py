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


def is_write(command: Exchange) -> bool:
    """True for anything that would write to the controller (typed or raw PUT)."""
    if isinstance(command, Put):
        return True
    return isinstance(command, Raw) and command.wire.lstrip(" \t")[:3].upper() == "PUT"


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
    if read_only and is_write(command):
        return refused(line, "PUT refused: read-only mode is on (nothing was sent)", wire)
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
        return Outcome(wire, ExitStatus.TRANSPORT, var, error=message, input_line=line)
    except TransportError as exc:
        text = escape_bytes(exc.raw) if isinstance(exc, BadReply) and exc.raw is not None else None
        return Outcome(
            wire, ExitStatus.TRANSPORT, var, response_text=text, error=str(exc), input_line=line
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
