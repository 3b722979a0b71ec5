"""Which controller a command talks to: ``-H HOST``, or the built-in simulator."""

from __future__ import annotations

import argparse
import sys
from collections.abc import AsyncIterator, Callable
from contextlib import AsyncExitStack, asynccontextmanager

from ..client import RacSession
from ..core import SIMULATOR_NOTICE
from ..recorder import FrameRecorder
from ..sim.server import SimulatorServer


@asynccontextmanager
async def open_session(
    args: argparse.Namespace, on_record_failure: Callable[[str], None] | None = None
) -> AsyncIterator[RacSession]:
    """A session to ``args.host``, or to an in-process simulator when no host was given;
    with ``--record``, a recorder that tells ``on_record_failure`` when it stops."""
    async with AsyncExitStack() as stack:
        if args.host:
            session = RacSession(args.host, args.port, timeout=args.timeout)
        else:
            sim = await stack.enter_async_context(SimulatorServer())
            print(f"rac-console: {SIMULATOR_NOTICE} (at {sim.host}:{sim.port})", file=sys.stderr)
            session = RacSession(sim.host, sim.port, timeout=args.timeout)
        if args.record:
            recorder = FrameRecorder(args.record, on_record_failure)
            stack.callback(recorder.close)
            session.add_frame_observer(recorder)
        stack.push_async_callback(session.close)
        yield session
