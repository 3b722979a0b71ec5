"""Which controller a command talks to: ``-H HOST``, or the built-in simulator."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager

from ..engine import SIMULATOR_NOTICE
from ..engine.recorder import FrameRecorder
from ..session import Session


@contextmanager
def open_session(
    args: argparse.Namespace, on_record_failure: Callable[[str], None] | None = None
) -> Iterator[Session]:
    """A session to ``args.host``, or to a simulator on a thread of this process when no
    host was given; with ``--record``, a recorder that tells ``on_record_failure`` when
    it stops."""
    with ExitStack() as stack:
        if args.host:
            session = Session(args.host, args.port, timeout=args.timeout)
        else:
            from ..sim.thread import SimulatorThread

            sim = stack.enter_context(SimulatorThread())
            print(f"rac-console: {SIMULATOR_NOTICE} (at {sim.host}:{sim.port})", file=sys.stderr)
            session = Session(sim.host, sim.port, timeout=args.timeout)
        if args.record:
            recorder = FrameRecorder(args.record, on_record_failure)
            stack.callback(recorder.close)
            session.add_frame_observer(recorder)
        stack.callback(session.close)
        yield session
