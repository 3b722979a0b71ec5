"""Which controller a command talks to: ``-H HOST``, ``-H PROFILE``, or the built-in
simulator; and what it lets be written."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator, Mapping
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..commands.policy import TargetProfile, WritePolicy, Writes
from ..commands.profiles import could_be_profile_name, match_profile
from ..engine import SIMULATOR_NOTICE
from ..engine.config import Config, load_config
from ..engine.recorder import FrameRecorder
from ..engine.transcript import FrameTranscript
from ..protocol import InputError
from ..protocol.request import Request
from ..protocol.text import terminal_safe
from ..session import ConnectFailed, Reply, Session
from ..session.endpoints import addresses

DEFAULT_PORT = 5006
OPEN = WritePolicy()


@dataclass(frozen=True)
class Target:
    """The target of a run, resolved once from ``-H``, ``-p``, ``--read-only`` and the
    config file (``args.target`` after :func:`settle_target`)."""

    host: str | None  # None: the built-in simulator
    port: int
    profile: TargetProfile | None = None  # -H NAME named a profile
    policy: WritePolicy = OPEN  # the profile's writes and allow (open without one)
    read_only: bool = False  # --read-only, or the profile's writes = "read-only"
    read_only_flag: bool = False  # --read-only itself (the console keeps it through connect)
    profiles: Mapping[str, TargetProfile] = field(default_factory=dict)
    config_path: Path | None = None
    config: Config | None = None  # the file as loaded ([settings] too)
    #: Said when the host cannot be reached: it was a bare name and no profile.
    unreachable_hint: str | None = None
    #: Said once at start: profiles whose host could not be resolved, matched by text only.
    notices: tuple[str, ...] = ()


def resolve_target(args: argparse.Namespace) -> Target:
    """The target ``args`` name; InputError (one line, naming the file) when the config
    file is broken: a broken file must not silently drop a profile's read-only guard."""
    config = load_config()
    flag = bool(args.read_only)
    port: int | None = args.port
    match = match_profile(config.profiles, args.host, port, addresses) if args.host else None
    profile = match.profile if match is not None else None
    notices = tuple(match.notices()) if match is not None else ()
    if profile is None:
        hint = None
        if args.host and could_be_profile_name(args.host):
            where = config.path if config.found else f"{config.path} (no such file)"
            hint = f"no profile named {args.host} in {where}"
        return Target(
            args.host,
            DEFAULT_PORT if port is None else port,
            read_only=flag,
            read_only_flag=flag,
            profiles=config.profiles,
            config_path=config.path,
            config=config,
            unreachable_hint=hint,
            notices=notices,
        )
    named = profile.name.casefold() == args.host.casefold()
    return Target(
        profile.host if named else args.host,  # at its address: the address typed
        profile.port if port is None else port,  # -p given: it wins
        profile,
        profile.policy,
        read_only=flag or profile.policy.writes is Writes.READ_ONLY,
        read_only_flag=flag,
        profiles=config.profiles,
        config_path=config.path,
        config=config,
        notices=notices,
    )


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


def write_policy(args: argparse.Namespace) -> WritePolicy:
    """What the target lets be written: the profile's ``writes`` and ``allow`` (open for
    a plain host or the simulator). ``args.read_only`` already holds a read-only
    profile's guard once :func:`settle_target` ran."""
    target: Target | None = getattr(args, "target", None)
    return (target if target is not None else resolve_target(args)).policy


def engine_target(args: argparse.Namespace) -> dict[str, Any]:
    """The console's and the REPL's Engine options for ``args.target``: the profile, its
    policy, every profile (for ``connect NAME``), ``--read-only`` itself (the engine adds
    a read-only profile's own) and ``--no-verify``."""
    target: Target = args.target
    return {
        "read_only": target.read_only_flag,
        "policy": target.policy,
        "profile": target.profile,
        "profiles": target.profiles,
        "verify": args.verify,
    }


class _HintedSession(Session):
    """A session to a bare name that is no profile: failing to connect says so."""

    def __init__(self, host: str, port: int, hint: str, *, timeout: float) -> None:
        super().__init__(host, port, timeout=timeout)
        self.hint = hint

    def connect(self) -> None:
        with self._hinted():
            super().connect()

    def exchange(
        self,
        request: Request,
        *,
        poll: bool = False,
        cancelled: Callable[[], bool] | None = None,
    ) -> Reply:
        with self._hinted():
            return super().exchange(request, poll=poll, cancelled=cancelled)

    @contextmanager
    def _hinted(self) -> Iterator[None]:
        try:
            yield
        except ConnectFailed as exc:
            raise ConnectFailed(f"{exc} ({self.hint})", problem=exc.problem) from None


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
    if target is None:
        target = getattr(args, "target", None) or resolve_target(args)
    with ExitStack() as stack:
        if target.host:
            if target.unreachable_hint:
                session: Session = _HintedSession(
                    target.host, target.port, target.unreachable_hint, timeout=args.timeout
                )
            else:
                session = Session(target.host, target.port, timeout=args.timeout)
        else:
            from ..sim.thread import SimulatorThread

            sim = stack.enter_context(SimulatorThread())
            print(f"rac-console: {SIMULATOR_NOTICE} (at {sim.host}:{sim.port})", file=sys.stderr)
            session = Session(sim.host, sim.port, timeout=args.timeout)
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
