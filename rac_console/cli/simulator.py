"""``rac-console sim``: serve the simulator until interrupted; ``--cell N``: N of them
playing a handshake; ``--replay CELL.jsonl`` of a recorded cell: one per target.

Whatever clients do, stderr gets a few lines and never a traceback: the server's own
notices are rate-limited, and so is anything asyncio would report (a callback that
raised, a warning) once routed through the same notices.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys
from collections.abc import Callable
from dataclasses import fields
from typing import Any

from ..protocol.text import terminal_safe
from ..sim.cell import CYCLE, GO, NAMES, PART_PLACED, SimulatedCell
from ..sim.controller import SimulatedController
from ..sim.faults import FaultSettings
from ..sim.notices import Notices
from ..sim.replay import DEFAULT_END, ReplayController, ReplayError, load_recordings
from ..sim.server import SimulatorServer, is_loopback


def _to_stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


class _ToNotices(logging.Handler):
    """asyncio's log records as rate-limited notices: one line each, no traceback."""

    def __init__(self, notices: Notices) -> None:
        super().__init__(logging.WARNING)
        self._notices = notices

    def emit(self, record: logging.LogRecord) -> None:
        text = record.getMessage().splitlines()[0] if record.getMessage() else record.levelname
        if record.exc_info and record.exc_info[1] is not None:
            text = f"{text}: {record.exc_info[1]!r}"
        self._notices.note("asyncio", f"asyncio: {text}")  # one kind: bounded whatever it says


def _quiet_asyncio(loop: asyncio.AbstractEventLoop, notices: Notices) -> logging.Handler:
    """Route what asyncio would print (with tracebacks) through ``notices``."""

    def handle(_: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        message = str(context.get("message") or "unexpected error")
        exc = context.get("exception")
        detail = f": {exc!r}" if exc else ""
        notices.note("internal", f"internal error: {message}{detail}")

    loop.set_exception_handler(handle)
    handler = _ToNotices(notices)
    log = logging.getLogger("asyncio")
    log.addHandler(handler)
    log.propagate = False
    return handler


async def serve(args: argparse.Namespace) -> int:
    """One simulator, a recorded cell's (one per target, ``--replay``) or a simulated
    cell's (``--cell N``), served until interrupted: all start or none does."""
    if not is_loopback(args.bind):
        print(
            f"rac-console: warning: the simulator listens on {args.bind}, beyond loopback: "
            "anyone who can reach this machine can read and write its variables",
            file=sys.stderr,
        )
    try:
        faults = FaultSettings(**{f.name: getattr(args, f.name) for f in fields(FaultSettings)})
        faults.check()
    except ValueError as exc:
        print(f"rac-console: {exc}", file=sys.stderr)
        return 2
    count = getattr(args, "sim_cell", None)
    if count is not None and getattr(args, "replay", None) is not None:
        print(
            "rac-console: --cell N or --replay FILE, not both "
            "(a recorded cell replays each of its targets on its own port)",
            file=sys.stderr,
        )
        return 2
    replays = _replay(args)
    if isinstance(replays, int):
        return replays
    names, controllers = _controllers(replays, count)
    if args.sim_port and args.sim_port + len(names) - 1 > 65535:
        print(f"rac-console: ports {args.sim_port} and up: past 65535", file=sys.stderr)
        return 2
    servers = [
        SimulatorServer(
            args.bind,
            args.sim_port + n if args.sim_port else 0,
            controller=controller,
            faults=faults,
            idle_timeout=getattr(args, "idle_timeout", 0),
            control=not getattr(args, "no_control", False),
            notify=_to_stderr if name is None else _named(name),
        )
        for n, (name, controller) in enumerate(zip(names, controllers, strict=True))
    ]
    cell = SimulatedCell(servers=servers) if count is not None else None
    started = await _start(servers, cell, args.bind)
    if started:
        return started
    handler = _quiet_asyncio(asyncio.get_running_loop(), servers[0].notices)
    for server in servers:
        if isinstance(server.controller, ReplayController):
            server.controller.notify = server.notices.note
            _to_stderr(
                f"rac-console sim: {server.controller.recording.describe(server.controller.end)}"
            )
    _say_listening(names, servers, count)
    if faults.active or faults.max_sessions:
        print(f"faults: {faults.describe()}", flush=True)
    try:
        await asyncio.gather(*(server.serve_forever() for server in servers))
    finally:
        if cell is not None:
            await cell.stop()
        else:
            await asyncio.gather(*(server.stop() for server in servers))
        log = logging.getLogger("asyncio")
        log.removeHandler(handler)
        log.propagate = True
    return 0


Controller = SimulatedController | ReplayController | None


def _controllers(
    replays: list[ReplayController] | None, count: int | None
) -> tuple[list[str | None], list[Controller]]:
    """Each simulator's name (None: the one simulator, as always) and controller."""
    if count is not None:
        return list(NAMES[:count]), [SimulatedController() for _ in range(count)]
    if replays is None:
        return [None], [None]
    if len(replays) == 1:  # one target's recording: replayed exactly as before
        return [None], [replays[0]]
    return [replay.recording.target for replay in replays], list(replays)


def _named(name: str) -> Callable[[str], None]:
    """A simulator's notices on stderr, each line naming it."""
    return lambda line: _to_stderr(f"{terminal_safe(name)}: {line}")


async def _start(servers: list[SimulatorServer], cell: SimulatedCell | None, bind: str) -> int:
    """Start them all (0), or none: exit status 3 after one line on stderr."""
    for n, server in enumerate(servers):
        try:
            await server.start()
        except (OSError, OverflowError, UnicodeError, ValueError) as exc:
            reason = getattr(exc, "strerror", None) or "not an address this machine has"
            print(f"rac-console: cannot listen on {bind}:{server.port}: {reason}", file=sys.stderr)
            await asyncio.gather(*(started.stop() for started in servers[:n]))
            return 3
    if cell is not None:
        cell.play()
    return 0


def _say_listening(
    names: list[str | None], servers: list[SimulatorServer], count: int | None
) -> None:
    if names == [None]:
        server = servers[0]
        print(f"RC8 simulator listening on {server.host}:{server.port} (Ctrl-C to stop)")
        return
    for name, server in zip(names, servers, strict=True):
        print(f"{terminal_safe(name or '')} listening on {server.host}:{server.port}")
    if count is not None and count > 1:
        print(
            f"a handshake: {NAMES[0]} sets its IO {PART_PLACED[1]} (part placed) every "
            f"{CYCLE:g} s, {NAMES[1]} answers with its IO {GO[1]} (go)"
        )
    print(f"Ctrl-C stops all {len(servers)}", flush=True)


def _replay(args: argparse.Namespace) -> list[ReplayController] | int | None:
    """The controllers serving ``--replay FILE``, one per target recorded (None without
    it), or exit status 2 after one line on stderr: a file that cannot be replayed, or
    --replay-end alone."""
    path, end = getattr(args, "replay", None), getattr(args, "replay_end", None)
    if path is None:
        if end is not None:
            print("rac-console: --replay-end needs --replay FILE", file=sys.stderr)
            return 2
        return None
    try:
        recordings = load_recordings(path)
    except ReplayError as exc:
        print(f"rac-console: {exc}", file=sys.stderr)
        return 2
    return [ReplayController(recording, end or DEFAULT_END) for recording in recordings]
