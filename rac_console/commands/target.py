"""Which controller a session talks to and what it lets be written, resolved once.

One pure function for every way a target is named: ``-H`` on the command line, the
console's and the REPL's ``connect``, and the CLI's one-shot commands. It is told how
to resolve a host (``resolve``), so it does no I/O of its own.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

from ..protocol.errors import InputError
from ..protocol.text import close_match, endpoint, terminal_safe
from .advice import COMMAND_LINE, Advice
from .policy import TargetProfile, WritePolicy, Writes

if TYPE_CHECKING:  # matching a name to a profile loads with the first host named
    from .cells import CellSpec
    from .profiles import Addresses

DEFAULT_PORT = 5006
#: What a target lets be written, as the status line says it.
WritesShown = Literal["open", "confirm", "read-only"]
OPEN = WritePolicy()


@dataclass(frozen=True)
class Target:
    """A controller (or the built-in simulator) and its rules."""

    host: str | None  # None: the built-in simulator
    port: int
    profile: TargetProfile | None = None  # the name typed was a profile, or its address
    policy: WritePolicy = OPEN  # the profile's writes and allow (open without one)
    read_only: bool = False  # --read-only, or the profile's writes = "read-only"
    read_only_flag: bool = False  # --read-only itself: kept through connect
    profiles: Mapping[str, TargetProfile] = field(default_factory=dict)  # connect NAME
    #: Said when the host cannot be reached: it was a bare name and no profile.
    unreachable_hint: str | None = None
    #: Said once: profiles whose host could not be resolved, matched by text only.
    notices: tuple[str, ...] = ()
    #: A simulator this program started (``--cell demo``), at a real address.
    simulated: bool = False

    @property
    def writes(self) -> WritesShown:
        """``open``, ``confirm`` or ``read-only``, as the status line says it."""
        if self.read_only or self.policy.writes is Writes.READ_ONLY:
            return "read-only"
        return "confirm" if self.policy.writes is Writes.CONFIRM else "open"

    @property
    def label(self) -> str | None:
        return self.profile.label if self.profile is not None else None


def resolve_target(
    host: str | None,
    port: int | None,
    *,
    profiles: Mapping[str, TargetProfile],
    read_only_flag: bool = False,
    plain_policy: WritePolicy = OPEN,
    resolve: Addresses | None = None,
    config_where: str | None = None,
) -> Target:
    """The target ``host`` names: a profile by name or by address (``127.1`` is
    ``127.0.0.1``), else a plain host with ``plain_policy``, else (None) the simulator,
    whose writes are open. ``port`` None: the profile's, or 5006. ``--read-only`` wins
    over any profile; of several profiles at one address the strictest applies.
    ``config_where`` names the config file in the hint for a bare name that is no profile."""
    if host is None:
        return Target(
            None,
            DEFAULT_PORT if port is None else port,
            read_only=read_only_flag,
            read_only_flag=read_only_flag,
            profiles=profiles,
        )
    from .profiles import find_profile, match_profile

    match = match_profile(profiles, host, port, resolve)
    named = find_profile(profiles, host)
    notices = tuple(match.notices())
    policy = match.policy
    if named is not None:  # the profile's host, at the port given or its own
        host, port = named.host, named.port if port is None else port
    port = DEFAULT_PORT if port is None else port
    if policy is None:
        return Target(
            host,
            port,
            policy=plain_policy,
            read_only=read_only_flag or plain_policy.writes is Writes.READ_ONLY,
            read_only_flag=read_only_flag,
            profiles=profiles,
            unreachable_hint=no_profile_hint(host, profiles, config_where),
            notices=notices,
        )
    if named is not None and port != named.port:
        notices += (_elsewhere(named, host, port, match.profile),)
    return Target(
        host,
        port,
        match.profile,
        policy,
        read_only=read_only_flag or policy.writes is Writes.READ_ONLY,
        read_only_flag=read_only_flag,
        profiles=profiles,
        notices=notices,
    )


def _elsewhere(named: TargetProfile, host: str, port: int, reached: TargetProfile | None) -> str:
    """Said when a profile's name is given another port: which controller that is."""
    if reached is None or reached is named:
        return (
            f"{named.name} is {endpoint(named.host, named.port)}; no profile names "
            f"{endpoint(host, port)}: {named.name}'s rules apply there"
        )
    return (
        f"{named.name} is {endpoint(named.host, named.port)}; {endpoint(host, port)} is "
        f"profile {reached.name}'s controller: the stricter rules of both apply"
    )


def one_controller_each(
    members: Sequence[tuple[str, Target]], addresses: Addresses
) -> list[tuple[str, Target]]:
    """A cell's members, unless two of them reach one controller (one endpoint, however
    written: their hosts as typed and as resolved): InputError naming both, since one
    controller is one session."""
    seen: list[tuple[str, int, frozenset[str]]] = []
    for name, target in members:
        host = target.host or "127.0.0.1"
        reached = (addresses(host) or frozenset()) | {host.casefold()}
        for other, port, theirs in seen:
            if port == target.port and theirs & reached:
                raise InputError(
                    f"{terminal_safe(other)} and {terminal_safe(name)} are one controller "
                    f"({endpoint(host, port)}): one session per controller; name it once"
                )
        seen.append((name, target.port, reached))
    return list(members)


def no_profile_hint(
    host: str, profiles: Mapping[str, TargetProfile], config_where: str | None = None
) -> str | None:
    """``no profile named cel3 in FILE`` (or with the profiles there are), and ``did you
    mean cell3?`` when a profile's name is close, when ``host`` looks like a profile's
    name rather than an address; None when it does not. Every front end says it: the
    console, the REPL, ``connect`` and the one-shot commands all resolve through here."""
    from .profiles import could_be_profile_name

    if not could_be_profile_name(host):
        return None
    guess = close_match(host, profiles)
    meant = f": did you mean {terminal_safe(guess)}?" if guess is not None else ""
    if config_where is not None:
        return f"no profile named {host} in {config_where}{meant}"
    known = f"profiles: {', '.join(sorted(profiles))}" if profiles else "the config file names none"
    return f"no profile named {host} ({known}){meant}"


def host_and_port(
    host: str | None, port: int | None, advice: Advice = COMMAND_LINE
) -> tuple[str | None, int | None]:
    """``-H HOST:PORT`` (or ``[v6]:PORT``) as ``connect`` reads it, ``-H NAME:PORT``
    too; ``-p`` with a port in ``-H`` too is refused unless both say the same. A
    refusal says how to write an address in ``advice``'s words."""
    if host is None or not (host.startswith("[") or host.count(":") == 1):
        return host, port
    from .language import parse_connect

    address = parse_connect(host, advice)
    if not address.port_given:
        return address.host, port
    if port is not None and port != address.port:
        raise InputError(
            f"-H {terminal_safe(host)} and -p {port} name two ports: give the port once"
        )
    return address.host, address.port


@dataclass(frozen=True)
class CellTargets:
    """The targets a cell names, each with its rules; or, for the demo cell with no
    ``[cell.demo]`` in the config file, none: its simulators are the front end's to start."""

    members: list[tuple[str, Target]]
    spec: CellSpec | None = None  # the [cell.NAME] table that named them
    demo: bool = False


def cell_targets(
    hosts: Sequence[str] | None,
    cell: str | None,
    *,
    profiles: Mapping[str, TargetProfile],
    cells: Mapping[str, CellSpec],
    addresses: Addresses,
    read_only_flag: bool = False,
    config_where: str | None = None,
    advice: Advice = COMMAND_LINE,
) -> CellTargets:
    """A cell's targets: the ``hosts`` given (profiles' names or addresses, ``-H a,b``),
    or the cell named ``cell`` in the config file; each resolved as ``-H`` resolves one
    and named by its profile (else as typed). InputError for a cell that is not there, a
    name that is no controller, or two names reaching one controller (what to do said
    in ``advice``'s words)."""
    from .cells import DEMO_CELL
    from .names import find_name

    def resolved(name: str) -> tuple[str, Target]:
        host, port = host_and_port(name, None, advice)  # a profile, HOST, HOST:PORT, [v6]:PORT
        if host is None or host == "sim":
            raise InputError(
                f"a cell's targets are controllers; sim is not one ({advice.demo_cell})"
            )
        target = resolve_target(
            host,
            port,
            profiles=profiles,
            read_only_flag=read_only_flag,
            resolve=addresses,
            config_where=config_where,
        )
        return (target.profile.name if target.profile is not None else name), target

    if hosts is not None:
        return CellTargets(one_controller_each([resolved(name) for name in hosts], addresses))
    assert cell is not None
    found = find_name(cells, cell)
    spec = cells[found] if found is not None else None
    if spec is None and cell.casefold() == DEMO_CELL:
        return CellTargets([], demo=True)
    if spec is None:
        known = ", ".join(sorted(cells)) or f"none in {config_where}"
        raise InputError(
            f"no cell named {cell} (cells: {known}); name one with [cell.{cell}] and "
            f'targets = ["cell3", "cell4"], or {advice.demo_cell}'
        )
    members = [resolved(name) for name in spec.targets]
    return CellTargets(one_controller_each(members, addresses), spec)
