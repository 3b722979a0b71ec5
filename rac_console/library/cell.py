"""A cell for a Python script: several controllers, one connection each, and lines
routed by ``@NAME`` as the console routes them (``rac.cell("line2")``).

The targets are those ``--cell NAME`` or ``-H a,b`` would open, each under its own
profile's rules; ``"demo"`` with no ``[cell.demo]`` in the config file starts the
console's demo simulators in this process. A line is planned and carried out by the
console's executor of routes (:class:`~rac_console.engine.cell.routes.Routes`), whose
targets here are the connections: ``@robotA put I 10 5`` runs on robotA's, through its
write gate, a line without ``@NAME`` on the current target's (``use NAME`` changes it).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Mapping, Sequence
from typing import TYPE_CHECKING

from ..commands.advice import LIBRARY
from ..commands.language import Command, Get, Put, Raw, Use
from ..commands.names import find_name
from ..commands.outcome import Outcome
from ..engine.cell.routes import Done, Line, Routes
from ..engine.published.feedback import Message
from ..engine.setup.targets import Members, cell_of, demo_members
from ..engine.setup.where import Where
from ..protocol import InputError
from ..session import DEFAULT_TIMEOUT
from .connection import Confirm, Connection
from .errors import Refused, UnknownTarget
from .results import Sent, Value, Written
from .target import ConfigPath, check_timeout, loaded, open_session

if TYPE_CHECKING:
    from ..engine.commands.registry import Registry
    from ..sim.cell import SimulatedCellThread

#: What a line of a cell may run from a script: one exchange on one target, or ``use``.
RUNS = "get, put, send, a raw GET:/PUT: line, or use NAME"


def cell(
    targets: str | Sequence[str],
    *,
    timeout: float = DEFAULT_TIMEOUT,
    read_only: bool = False,
    confirm: Confirm | None = None,
    yes: bool = False,
    config: ConfigPath = None,
    direct: bool = False,
) -> Cell:
    """The cell ``targets`` names: a ``[cell.NAME]`` of the config file (``"demo"``: the
    demo simulators when the file names none), or a list of targets (profiles' names or
    addresses, as ``-H a,b``). Every target is connected before this returns; the
    options apply to each as :func:`~rac_console.connect` applies them (``direct``
    too)."""
    seconds = check_timeout(timeout)
    hosts = None
    if not isinstance(targets, str):
        hosts = list(targets) if isinstance(targets, Sequence) else []
        if not hosts or not all(isinstance(name, str) for name in hosts):
            raise Refused(f"a cell is a [cell.NAME]'s name or a list of targets, not {targets!r}")
    settings = loaded(config)
    try:
        found = cell_of(
            hosts,
            targets if isinstance(targets, str) else None,
            settings,
            read_only_flag=bool(read_only),
            advice=LIBRARY,
        )
    except InputError as exc:
        raise Refused(str(exc)) from None
    simulated = None
    members = found.members
    if found.demo:
        simulated, members = _demo(bool(read_only))
    connections: dict[str, Connection] = {}
    try:
        for name, target in members:
            session, _ = open_session(target, seconds, bool(direct))
            connections[name] = Connection(target, session, confirm=confirm, yes=yes)
    except BaseException:
        for opened in connections.values():
            opened.close()
        if simulated is not None:
            simulated.stop()
        raise
    return Cell(connections, simulated)


def _demo(read_only: bool) -> tuple[SimulatedCellThread, Members]:
    """The console's demo cell: simulators playing a handshake, in this process."""
    from ..sim.cell import SimulatedCellThread

    simulated = SimulatedCellThread().start()
    return simulated, demo_members(simulated, read_only)


class _OnConnections:
    """The executor's targets (:class:`~rac_console.engine.cell.routes.Targets`) for a
    script's cell: an exchange runs inline on the target's connection; any other command
    is answered with a refusal, nothing sent."""

    def __init__(self, connections: Mapping[str, Connection]) -> None:
        self._connections = connections

    def run(self, name: str, command: Command, line: Line, done: Done, whole: bool) -> None:
        if isinstance(command, Get | Put | Raw):
            done((self._connections[name]._exchange(command),))
        else:
            done((Message(_not_run(line.text or ""), "error"),))


def _not_run(line: str) -> str:
    return f"a cell's line in a script runs {RUNS}, not {line.strip()!r}"


def _builtin() -> Registry:
    """The console's commands, loaded with the first line planned."""
    from ..engine.commands.builtin import BUILTIN

    return BUILTIN


class Cell(Mapping[str, Connection]):
    """The cell's connections by name (``cell["robotA"]``, any case), and :meth:`run` for
    lines routed by ``@NAME``. A context manager; :meth:`close` closes every connection."""

    def __init__(
        self, connections: dict[str, Connection], simulated: SimulatedCellThread | None = None
    ) -> None:
        self._connections = connections
        self._simulated = simulated
        self._names = tuple(connections)
        members = [(name, connection._target) for name, connection in connections.items()]
        self._routes = Routes(_OnConnections(connections), members, _builtin, Where.RUN, LIBRARY)
        self._numbers = itertools.count(1)

    @property
    def names(self) -> tuple[str, ...]:
        """The targets' names, in the cell's order."""
        return self._names

    @property
    def current(self) -> str:
        """The target a line without ``@NAME`` runs on."""
        return self._routes.current

    def __getitem__(self, name: str) -> Connection:
        found = find_name(self._names, name) if isinstance(name, str) else None
        if found is None:
            raise UnknownTarget(
                f"no target named {name!r} in this cell; it holds {', '.join(self._names)}"
            )
        return self._connections[found]

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)

    def __repr__(self) -> str:
        return f"<rac.Cell {', '.join(self._names)} (current {self.current})>"

    def use(self, name: str) -> None:
        """Lines without ``@NAME`` run on ``name`` from now on (the console's ``use``)."""
        self.run(f"use {name}")

    def run(self, line: str) -> Value | Written | Sent | None:
        """One line of the console's language, routed as the console routes it: a get's
        value, a put's :class:`Written`, a raw line's :class:`Sent`; None for ``use``, a
        blank line or a comment. Other commands, and lines that run elsewhere than one
        target (a chained wait, publish), are Refused with nothing sent: call the
        connection's methods (``cell["robotA"].watch(...)``) for the rest."""
        if not isinstance(line, str):
            raise Refused(f"a line is text such as '@robotA get I 10', not {line!r}")
        answer = self._routes.answer(Line(next(self._numbers), line))
        command = answer.command
        if command is not None and not isinstance(command, Get | Put | Raw | Use):
            raise Refused(_not_run(line))
        for name, feedback in answer.parts:
            for said in feedback:
                if isinstance(said, Outcome) and name is not None:
                    assert isinstance(command, Get | Put | Raw)
                    return self._connections[name]._answer(command, said)
                if isinstance(said, Message) and said.level == "error":
                    raise Refused(said.text)
        return None

    def close(self) -> None:
        """Close every connection (and the demo's simulators)."""
        for connection in self._connections.values():
            connection.close()
        if self._simulated is not None:
            self._simulated.stop()

    def __enter__(self) -> Cell:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
