"""``rac-console check``: what stands between this computer and the controller.

Composes the session's probe, the pure words of each step and the presentation; sends
only GETs, so it is allowed with ``--read-only`` and on a read-only profile.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from contextlib import ExitStack

from ..commands.check import CheckReport, report_json
from ..commands.outcome import ExitStatus
from ..commands.target import Target
from ..engine.files.recorder import FrameRecorder
from ..engine.files.transcript import FrameTranscript
from ..present.check import check_lines
from ..present.render import make_console, print_error
from ..protocol import InputError
from ..session.diagnose import diagnose


def check(args: argparse.Namespace) -> ExitStatus:
    """Run the steps against the target (``args.target``, settled from ``-H``, ``-p`` and
    the config file; the built-in simulator without ``-H``), print one line per step or
    one JSON object; 0 all ok, 1 the GET answered an error, 3 a connection step failed."""
    target: Target = args.target
    err = make_console(stderr=True)
    local_failed = False

    def local_failure(message: str) -> None:
        nonlocal local_failed
        print_error(err, message)
        local_failed = True

    with ExitStack() as stack:
        host, port, simulator = target.host, target.port, target.host is None
        if host is None:
            from ..engine import SIMULATOR_NOTICE
            from ..sim.thread import SimulatorThread

            sim = stack.enter_context(SimulatorThread())
            host, port = sim.host, sim.port
            print(f"rac-console: {SIMULATOR_NOTICE} (at {sim.host}:{sim.port})", file=sys.stderr)
        try:
            observers = _observers(args, stack, local_failure)
        except InputError as exc:
            print_error(err, str(exc))
            return ExitStatus.REFUSED
        report = diagnose(host, port, timeout=args.timeout, observers=observers)
    profile = target.profile.name if target.profile is not None else None
    _show(args, report, profile, simulator, target.unreachable_hint)
    if not simulator:
        from .agent import holder_said

        said = holder_said(host, port)
        if said is not None:
            print(f"rac-console: {said}", file=sys.stderr)  # stdout and --json as before
    status = report.status
    return ExitStatus.LOCAL_IO if local_failed and status == ExitStatus.OK else status


def _observers(
    args: argparse.Namespace, stack: ExitStack, on_failure: Callable[[str], None]
) -> list[FrameRecorder | FrameTranscript]:
    """``--record`` and ``--log``: the check's frames too, as every command's."""
    files: list[FrameRecorder | FrameTranscript] = []
    if args.record:
        files.append(FrameRecorder(args.record, on_failure))
        stack.callback(files[-1].close)
    if getattr(args, "transcript", None):
        files.append(FrameTranscript(args.transcript, on_failure))
        stack.callback(files[-1].close)
    return files


def _show(
    args: argparse.Namespace,
    report: CheckReport,
    profile: str | None,
    simulator: bool,
    no_profile: str | None,
) -> None:
    if args.json:
        data = report_json(report, profile, simulator, no_profile)
        if (name := getattr(args, "member_name", None)) is not None:
            data = {"target": name} | data
        sys.stdout.write(json.dumps(data) + "\n")
        sys.stdout.flush()
        return
    out = make_console()
    for line in check_lines(report, profile, simulator, no_profile):
        out.print(line, soft_wrap=True)
