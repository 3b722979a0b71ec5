"""connect and disconnect: another target, with its rules, at a terminal."""

from __future__ import annotations

from collections.abc import Sequence

from ....commands.check import check_pointer
from ....commands.language import Connect, Simple, Step, Use, parse_connect, parse_use
from ....commands.routing import Reach, Scope, Traits
from ....commands.target import Target, resolve_target
from ....session import ConnectFailed, Disconnected
from ....session.endpoints import addresses
from ...published.events import Feedback, Message, shown_label
from ..context import CommandContext, JobContext
from ..registry import (
    AT_A_TERMINAL,
    CommandSpec,
    EngineSpec,
    Option,
    Sources,
    Where,
    no_argument,
)


def run_connect(context: CommandContext, command: Connect, line: str | None) -> list[Feedback]:
    """``connect PROFILE``, ``connect sim`` or ``connect HOST[:PORT]``: the target changes,
    and with it the profile (label, colour) and the write rules: a profile's, the
    simulator's (open), or for a plain host the ones the engine started with. The
    command line's ``--read-only`` stays whatever the target."""
    rules = context.rules
    given = command.port if command.port_given else None
    target = resolve_target(
        command.host,
        given,
        profiles=rules.profiles,
        read_only_flag=rules.read_only_flag,
        plain_policy=context.plain_policy,
        resolve=addresses,
    )
    for notice in target.notices:
        context.alert(notice)
    context.switch_target(target)
    controller = context.controller
    assert controller is not None
    try:
        controller.connect()
    except (ConnectFailed, Disconnected) as exc:
        if isinstance(exc, ConnectFailed):
            context.connect_failed(exc)
        text = f"{exc}; will keep retrying while variables are watched"
        text += f" {check_pointer(command.host, given)}"
        return [Message(text, "error")]
    return [Message(_connected(context, target))]


def _connected(context: CommandContext, target: Target) -> str:
    writes = "read-only" if target.read_only else f"writes {target.policy.writes.value}"
    if target.host is None:
        context.note("connected to the built-in simulator")
        return f"connected to the built-in simulator ({writes})"
    host, port = target.host, target.port
    context.note(f"connected to {host}:{port}")
    profile = target.profile
    if profile is None:
        rules = f" ({writes})" if writes != "writes open" else ""
        return f"connected to LIVE controller {host}:{port}{rules}"
    label = shown_label(profile.label or profile.name)
    allow = profile.policy.allow
    rules = f", allow {', '.join(map(str, allow)) or 'nothing'}" if allow is not None else ""
    return (
        f"connected to {label} (profile {profile.name}): LIVE controller {host}:{port}, "
        f"{writes}{rules}"
    )


def run_disconnect(context: CommandContext, command: Simple, line: str | None) -> list[Feedback]:
    context.disconnect()
    context.note("disconnected")
    return [
        Message(
            "disconnected: connect HOST[:PORT] or connect PROFILE to talk to a "
            "controller, connect sim for the built-in simulator"
        )
    ]


def _targets(args: list[str], sources: Sources) -> Sequence[Option]:
    return [("sim", "the built-in simulator"), *sources.targets] if not args else ()


def run_use(context: JobContext, command: Use, line: str | None) -> list[Feedback]:
    """``use`` run by one engine: it has one target (a cell runs ``use`` itself)."""
    return [
        Message(
            "use picks the current target of a cell, and one target is open here: open "
            "several with -H cell3,cell4 or --cell NAME",
            "error",
        )
    ]


def _cell_targets(args: list[str], sources: Sources) -> Sequence[Option]:
    return list(sources.cell) if not args else ()


SPECS = (
    EngineSpec(
        "connect",
        "HOST[:PORT]",
        "talk to a controller (port 5006 by default), a profile, or sim",
        parse_connect,
        run_connect,
        "connect 192.168.0.1",
        (
            "connect PROFILE: a [target.PROFILE] of the config file, with its label, "
            "colour and write rules (writes, allow), e.g. connect cell3",
            "connect sim: back to the built-in simulator (writes open)",
            "connect HOST[:PORT]: no profile; --read-only stays whatever the target",
        ),
        complete=_targets,
        types=(Connect,),
        traits=Traits(scope=Scope.ONE_TARGET, reaches=Reach.NETWORK),
    ),
    CommandSpec(
        "use",
        "NAME",
        "make a target of the cell the current one (lines without @NAME run there)",
        parse_use,
        run_use,
        "use cell4",
        (
            "@NAME LINE runs one line on another target: @cell4 get I 10",
            "with several targets open, a write goes to the current one or to its @NAME",
        ),
        where=AT_A_TERMINAL | {Where.RUN},
        complete=_cell_targets,
        types=(Use,),
        traits=Traits(scope=Scope.CELL),
    ),
    EngineSpec(
        "disconnect",
        "",
        "close the session and stop polling",
        no_argument(Step.DISCONNECT),
        run_disconnect,
        types=(Simple,),
    ),
)
