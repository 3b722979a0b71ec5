"""Which controller a command talks to: ``-H HOST``, ``-H PROFILE``, or the built-in
simulator; and what it lets be written.

The session, the frame files and the host lookup are imported when a session is
opened or a host is looked up: the console settles its target before its first
paint, which needs none of them.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from typing import TYPE_CHECKING

from ..commands.target import Target, host_and_port
from ..engine.setup.config import load_config
from ..engine.setup.targets import one_target, session_to
from ..protocol.errors import InputError
from ..protocol.text import terminal_safe

if TYPE_CHECKING:
    from ..session import Session


def resolve_target(args: argparse.Namespace) -> Target:
    """The target ``-H``, ``-p`` and ``--read-only`` name, by the one resolver the
    console's ``connect`` uses too; InputError (one line, naming the file) when the
    config file is broken: a broken file must not silently drop a profile's guard."""
    config = load_config()
    host, port = host_and_port(args.host, args.port)
    return one_target(host, port, config, read_only_flag=bool(args.read_only))


def settle_target(args: argparse.Namespace) -> bool:
    """Resolve the target once for every mode: ``args.target`` holds it, and ``host``,
    ``port`` and ``read_only`` become the profile's (so every mode reading them is
    guarded). False, after one line on stderr, when the config file is broken."""
    try:
        target = resolve_target(args)
    except InputError as exc:
        print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
        return False
    args.target = target
    args.host, args.port, args.read_only = target.host, target.port, target.read_only
    if args.command is not None:  # the console shows them in its results pane
        for notice in target.notices:
            print(f"rac-console: {notice}", file=sys.stderr)
    return True


@contextmanager
def open_session(
    args: argparse.Namespace,
    on_record_failure: Callable[[str], None] | None = None,
    target: Target | None = None,
) -> Iterator[Session]:
    """A session to the target (``target``, else ``args.target``, else resolved from
    ``args`` here), or to a simulator on a thread of this process when it names no host;
    with ``--record`` (and ``--log``), a recorder that tells ``on_record_failure`` when it stops.

    Raises InputError when the config file is broken (only when not resolved before)."""
    from ..engine.files.recorder import FrameRecorder
    from ..engine.files.transcript import FrameTranscript

    if target is None:
        target = getattr(args, "target", None) or resolve_target(args)
    with ExitStack() as stack:
        session, sim = session_to(target, args.timeout)
        if sim is not None:
            from ..engine import SIMULATOR_NOTICE

            stack.callback(sim.stop)
            print(f"rac-console: {SIMULATOR_NOTICE} (at {sim.host}:{sim.port})", file=sys.stderr)
        if args.record:
            recorder = FrameRecorder(args.record, on_record_failure)
            stack.callback(recorder.close)
            session.add_frame_observer(recorder)
        if getattr(args, "transcript", None):  # --log FILE: said and stopped as --record
            transcript = FrameTranscript(args.transcript, on_record_failure)
            stack.callback(transcript.close)
            session.add_frame_observer(transcript)
        stack.callback(session.close)
        yield session
