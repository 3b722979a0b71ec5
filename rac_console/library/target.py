"""Which controller a script talks to, and by which rules: resolved as ``-H`` resolves it
(a host, ``host:port``, a profile's name in any case, or ``sim``), the config file's
profiles applying as they do in the console (the strictest at the endpoint reached).
"""

from __future__ import annotations

import logging
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

from ..commands.advice import LIBRARY
from ..commands.check import CheckReport, Problem, StepName, StepResult, hint
from ..commands.target import Target, host_and_port
from ..engine.setup.config import Config, load_config
from ..engine.setup.targets import one_target, session_to
from ..protocol import InputError
from ..protocol.text import terminal_safe
from ..session import ConnectFailed, Disconnected, Session
from .errors import ConnectionFailed, Refused

if TYPE_CHECKING:
    from ..sim.thread import SimulatorThread

#: What the library says that is no error (a profile whose host cannot be resolved).
log = logging.getLogger("rac_console")

#: The target that names the built-in simulator, as ``connect sim`` does.
SIMULATOR = "sim"

ConfigPath = str | os.PathLike[str] | None


def loaded(config: ConfigPath) -> Config:
    """The config file ``config`` names (``~`` expanded), else the one the command line
    reads (its ``RAC_CONSOLE_CONFIG``, or the user's); Refused for one that is not there
    or is broken, naming it (either must not quietly drop a profile's guard)."""
    named = os.fspath(config) if isinstance(config, str | os.PathLike) else None
    if config is not None and (not isinstance(named, str) or not named.strip()):
        raise Refused(f"config is the path of a config file, not {config!r}")
    try:
        if config is None:
            return load_config()
        return load_config(Path(config), named_by="config")
    except InputError as exc:
        raise Refused(str(exc)) from None


def resolve(target: str, port: int | None, read_only: bool, config: Config) -> Target:
    """The target ``target`` names, with its profile's rules; Refused for a name or a
    port that cannot be one."""
    if not isinstance(target, str) or not target.strip():
        raise Refused(f"connect to a host, host:port, a profile's name or 'sim', not {target!r}")
    if port is not None and (isinstance(port, bool) or not isinstance(port, int)):
        raise Refused(f"port is a number from 1 to 65535, got {port!r}")
    if port is not None and not 0 < port < 65536:
        raise Refused(f"port must be a number from 1 to 65535, got {port}")
    try:
        if target == SIMULATOR:
            if port is not None:
                raise InputError(
                    f"port={port} does not apply to 'sim': the built-in simulator listens "
                    "on a free port of its own (rc.port says which); nothing was started"
                )
            host, given = None, port
        else:
            host, given = host_and_port(target, None, LIBRARY)
            if given is not None and port is not None and given != port:
                raise InputError(
                    f"{terminal_safe(target)} and port={port} name two ports: give the port once"
                )
            given = port if given is None else given
        resolved = one_target(host, given, config, read_only_flag=read_only)
    except InputError as exc:
        raise Refused(str(exc)) from None
    for notice in resolved.notices:
        log.warning("%s", notice)
    return resolved


def check_timeout(timeout: float) -> float:
    """A timeout in seconds, more than 0; Refused otherwise."""
    if (
        isinstance(timeout, bool)
        or not isinstance(timeout, int | float)
        or not math.isfinite(timeout)
        or timeout <= 0
    ):
        raise Refused(f"timeout is a number of seconds above 0, got {timeout!r}")
    return float(timeout)


def open_session(
    target: Target, timeout: float, direct: bool = False
) -> tuple[Session, SimulatorThread | None]:
    """A session to ``target``, connected (ConnectionFailed with ``check``'s words when
    it cannot be), or to the built-in simulator started here when it names no host.
    Through the running agent that holds ``target``, unless ``direct``."""
    if target.host is not None and not direct:
        from ..agent.requests import attach_requests

        via = attach_requests(target, timeout)
        if via is not None:
            return via, None
    session, simulator = session_to(target, timeout)
    try:
        session.connect()
    except (ConnectFailed, Disconnected) as exc:
        session.close()
        if simulator is not None:
            simulator.stop()
        raise connection_failed(exc, Endpoint(session.host, session.port, timeout)) from None
    return session, simulator


class Endpoint(NamedTuple):
    """Where a session goes, and its timeout: what ``check``'s advice names."""

    host: str
    port: int
    timeout: float


def connection_failed(
    failure: ConnectFailed | Disconnected, at: Endpoint, message: str | None = None
) -> ConnectionFailed:
    """A failure to connect as the library says it: the session's words (or ``message``),
    then what ``rac-console check`` says to check for it."""
    problem: Problem = failure.problem if isinstance(failure, ConnectFailed) else "closed"
    step: StepName = "resolve" if problem == "unknown host" else "connect"
    advice = hint(
        StepResult(step, False, problem=problem), CheckReport(at.host, at.port, (), at.timeout)
    )
    text = message or str(failure)
    return ConnectionFailed(f"{text}: {advice}" if advice else text, problem=problem, hint=advice)
