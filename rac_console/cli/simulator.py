"""``rac-console sim``: serve the simulator until interrupted.

Whatever clients do, stderr gets a few lines and never a traceback: the server's own
notices are rate-limited, and so is anything asyncio would report (a callback that
raised, a warning) once routed through the same notices.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys
from dataclasses import fields
from typing import Any

from ..sim.faults import FaultSettings
from ..sim.notices import Notices
from ..sim.replay import DEFAULT_END, ReplayController, ReplayError, load_recording
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
    replay = _replay(args)
    if isinstance(replay, int):
        return replay
    server = SimulatorServer(
        args.bind,
        args.sim_port,
        controller=replay,
        faults=faults,
        idle_timeout=getattr(args, "idle_timeout", 0),
        control=not getattr(args, "no_control", False),
        notify=_to_stderr,
    )
    try:
        await server.start()
    except (OSError, UnicodeError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or "not an address this machine has"
        print(
            f"rac-console: cannot listen on {args.bind}:{args.sim_port}: {reason}", file=sys.stderr
        )
        return 3
    handler = _quiet_asyncio(asyncio.get_running_loop(), server.notices)
    if replay is not None:
        replay.notify = server.notices.note
        _to_stderr(f"rac-console sim: {replay.recording.describe(replay.end)}")
    print(f"RC8 simulator listening on {server.host}:{server.port} (Ctrl-C to stop)", flush=True)
    if faults.active or faults.max_sessions:
        print(f"faults: {faults.describe()}", flush=True)
    try:
        await server.serve_forever()
    finally:
        await server.stop()
        log = logging.getLogger("asyncio")
        log.removeHandler(handler)
        log.propagate = True
    return 0


def _replay(args: argparse.Namespace) -> ReplayController | int | None:
    """The controller serving ``--replay FILE`` (None without it), or exit status 2
    after one line on stderr: a file that cannot be replayed, or --replay-end alone."""
    path, end = getattr(args, "replay", None), getattr(args, "replay_end", None)
    if path is None:
        if end is not None:
            print("rac-console: --replay-end needs --replay FILE", file=sys.stderr)
            return 2
        return None
    try:
        recording = load_recording(path)
    except ReplayError as exc:
        print(f"rac-console: {exc}", file=sys.stderr)
        return 2
    return ReplayController(recording, end or DEFAULT_END)
