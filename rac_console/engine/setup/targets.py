"""The targets a front end names, resolved with the config file's profiles, and the
sessions to them: one target (``-H``, ``rac.connect``), a cell's (``--cell``, ``-H a,b``,
``rac.cell``), the demo cell's simulators. The command line and the library call these
alike; what differs between them (how an address or a port was given, what a refusal
says to do) is theirs to say.

The sessions, the simulators and the host lookup are imported when used: the console
settles its target before its first paint, which needs none of them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...commands.advice import COMMAND_LINE, Advice
from ...commands.target import CellTargets, Target, cell_targets, resolve_target
from .config import Config

if TYPE_CHECKING:
    from collections.abc import Sequence

    from ...session import Session
    from ...sim.cell import SimulatedCellThread
    from ...sim.thread import SimulatorThread

#: A cell's targets by name, in its order.
Members = list[tuple[str, Target]]


def addresses(host: str) -> frozenset[str] | None:
    """:func:`~rac_console.session.endpoints.addresses`, imported when a host is named
    (the package of sessions is not needed to start the console)."""
    from ...session.endpoints import addresses as resolved

    return resolved(host)


def one_target(
    host: str | None, port: int | None, config: Config, *, read_only_flag: bool
) -> Target:
    """The target ``host`` (None: the simulator) at ``port`` names under ``config``'s
    profiles: the strictest at the endpoint reached (see
    :func:`~rac_console.commands.target.resolve_target`)."""
    return resolve_target(
        host,
        port,
        profiles=config.profiles,
        read_only_flag=read_only_flag,
        resolve=addresses,
        config_where=config.named,
    )


def cell_of(
    hosts: Sequence[str] | None,
    cell: str | None,
    config: Config,
    *,
    read_only_flag: bool,
    advice: Advice = COMMAND_LINE,
) -> CellTargets:
    """The targets of ``hosts`` or of the cell named ``cell`` in ``config`` (see
    :func:`~rac_console.commands.target.cell_targets`); InputError said in ``advice``'s
    words."""
    return cell_targets(
        hosts,
        cell,
        profiles=config.profiles,
        cells=config.cells,
        addresses=addresses,
        read_only_flag=read_only_flag,
        config_where=config.named,
        advice=advice,
    )


def demo_members(simulated: SimulatedCellThread, read_only: bool) -> Members:
    """The demo cell's targets: ``simulated``'s simulators at their real addresses, said
    to be simulators (the console says so under its banner)."""
    return [
        (
            name,
            Target(host, port, read_only=read_only, read_only_flag=read_only, simulated=True),
        )
        for name, host, port in simulated.cell.addresses
    ]


def session_to(target: Target, timeout: float) -> tuple[Session, SimulatorThread | None]:
    """A session to ``target`` (not yet connected), or, when it names no host, to the
    built-in simulator started here on a thread of this process, which the caller stops."""
    from ...session import Session

    if target.host is not None:
        session = Session(
            target.host, target.port, timeout=timeout, unreachable_hint=target.unreachable_hint
        )
        return session, None
    from ...sim.thread import SimulatorThread

    simulator = SimulatorThread().start()
    return Session(simulator.host, simulator.port, timeout=timeout), simulator
