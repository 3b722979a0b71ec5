"""Which controllers a command talks to when it is several: ``-H cell3,cell4`` or
``--cell NAME``; each target resolved by the one resolver ``-H`` uses alone.

``--cell demo`` (with no ``[cell.demo]`` in the config) opens simulators playing a
handshake, started here, on a thread of this process, for as long as the command runs.
"""

from __future__ import annotations

import argparse
import atexit
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING

from ..commands.cells import not_open, split_hosts
from ..commands.names import find_name
from ..protocol import InputError
from ..protocol.text import terminal_safe

if TYPE_CHECKING:
    from ..engine.setup.targets import Members

#: Simulators of ``--cell demo``.
DEMO_TARGETS = 2


def settle_cell(args: argparse.Namespace) -> bool | None:
    """``args.cell_targets`` set to the cell's (name, target) pairs, and ``args.target``
    to the first (so what reads one target reads the current one); None when the
    command names one target (nothing changes); False after one line on stderr."""
    try:
        members = _members(args)
    except InputError as exc:
        print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
        return False
    if members is None:
        args.cell_targets = None
        return None
    args.cell_targets = members
    args.target = members[0][1]
    args.host, args.port, args.read_only = args.target.host, args.target.port, args.target.read_only
    return True


def pick_member(args: argparse.Namespace) -> str | None:
    """``get``/``put``/``send`` on a cell: the first word names the target (``get @cell3
    I 10``), which becomes the command's one target. Its name; InputError when the
    first word names none. None when no cell is open (nothing changes)."""
    members = getattr(args, "cell_targets", None)
    if not members:
        return None
    names = [name for name, _ in members]
    first = args.words[0] if args.words else ""
    example = f"rac-console {args.command} @{names[0]} I 10"
    if not first.startswith("@"):
        raise InputError(
            f"several targets are open ({', '.join(names)}): name the one to "
            f"{'write' if args.command == 'put' else 'ask'} first, e.g. {example}"
        )
    name = find_name(names, first[1:])
    if name is None:
        raise not_open(first[1:], names)
    found = dict(members)[name]
    args.words = args.words[1:]
    args.target, args.cell_targets = found, None
    args.host, args.port, args.read_only = found.host, found.port, found.read_only
    return name


def words_by_member(
    words: list[str], args: argparse.Namespace
) -> tuple[list[str], dict[str, list[str]]]:
    """``watch IO 128 @robotA I 10 @robotB IO 64``: the words for every target (before
    any ``@NAME``), and each named target's own, by its name as the cell writes it.
    InputError for a name the cell does not hold, or ``@NAME`` with no cell open."""
    members = getattr(args, "cell_targets", None)
    names = [name for name, _ in members] if members else []
    common: list[str] = []
    own: dict[str, list[str]] = {}
    current = common
    for word in words:
        if not word.startswith("@"):
            current.append(word)
            continue
        if not names:
            raise InputError(
                f"{word} names a target of a cell: open one with --cell NAME or -H a,b"
            )
        name = find_name(names, word[1:])
        if name is None:
            raise not_open(word[1:], names)
        current = own.setdefault(name, [])
    return common, own


def each_member(args: argparse.Namespace, run: Callable[[argparse.Namespace], int]) -> int:
    """``check`` and ``latency`` on a cell: each target in turn, its name first (a line
    on stdout, or ``"target"`` in each JSON object); the worst status."""
    worst = 0
    for name, target in args.cell_targets:
        args.target, args.member_name = target, name
        args.host, args.port, args.read_only = target.host, target.port, target.read_only
        if not args.json:
            print(f"{name}:", flush=True)
        worst = max(worst, int(run(args)))
    return worst


def _members(args: argparse.Namespace) -> Members | None:
    hosts = split_hosts(args.host)
    cell = getattr(args, "cell", None)
    if cell is None and hosts is None:
        return None
    if cell is not None and args.host is not None:
        raise InputError(f"--cell {cell} and -H {args.host}: give one (a cell names its targets)")
    if args.port is not None:
        raise InputError("-p applies to one target; in a cell each profile has its port")
    from ..engine.setup.config import load_config
    from ..engine.setup.targets import cell_of

    found = cell_of(hosts, cell, load_config(), read_only_flag=bool(args.read_only))
    args.cell_watch = ()
    if found.demo:
        return _demo(args)
    if found.spec is not None:
        args.cell_watch = found.spec.watch
        args.cell_publish = found.spec.publish
    return found.members


def _demo(args: argparse.Namespace) -> Members:
    """Simulators playing a handshake, said to be simulators (on stderr; the console
    under its banner), and the handshake watched from the start."""
    from ..engine.setup.targets import demo_members
    from ..sim.cell import DEMO_WATCH, SimulatedCellThread

    simulated = SimulatedCellThread(DEMO_TARGETS).start()
    atexit.register(simulated.stop)
    if args.command is not None:
        names = " and ".join(name for name, _, _ in simulated.cell.addresses)
        print(
            f"rac-console: --cell demo: {names} are simulators playing a handshake, not "
            "controllers",
            file=sys.stderr,
        )
    args.cell_watch = DEMO_WATCH
    return demo_members(simulated, bool(args.read_only))
