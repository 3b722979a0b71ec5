"""A connection to one controller for a Python script: ``rac.connect(...)``.

Every request goes through :meth:`Connection._exchange`, the one place the library meets
the controller: a read is sent as the console sends it, a write crosses the console's
write gate (read-only, the profile's ``allow``, the confirm answer, the read-back, an
unknown outcome said as unknown). Requests are taken one at a time under a lock, so
threads may share a connection; the session below is owned by whichever thread holds it.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Literal, overload

from ..commands.language import (
    WATCH_USAGE,
    Exchange,
    Get,
    Put,
    Raw,
    VarRef,
    parse_seconds,
    parse_var_list,
)
from ..commands.outcome import Outcome
from ..commands.target import Target
from ..engine.exchange.gate import WriteGate
from ..protocol import InputError, Variant
from ..session import DEFAULT_TIMEOUT, ConnectFailed, Session
from .answers import sent_of, value_of, written_of
from .errors import Refused
from .results import Reading, Sent, Value, Written
from .target import ConfigPath, Endpoint, check_timeout, loaded, open_session, resolve
from .values import plain_value, put_command, python_value, variable

if TYPE_CHECKING:
    from ..sim.thread import SimulatorThread

#: Asked before each write to a ``confirm`` profile: (the variable as the console names
#: it, its value now or None, the value to write) -> write it?
Confirm = Callable[[str, "Value | None", Value], bool]

#: A watch's default period, in seconds.
EVERY = 1.0


def connect(
    target: str,
    *,
    port: int | None = None,
    timeout: float = DEFAULT_TIMEOUT,
    read_only: bool = False,
    confirm: Confirm | None = None,
    yes: bool = False,
    config: ConfigPath = None,
    direct: bool = False,
) -> Connection:
    """A connection to ``target``: a host, ``host:port``, a profile's name (in any case)
    or ``"sim"`` (the built-in simulator, started in this process). The config file's
    profiles apply as in the console: the strictest at the endpoint reached, whichever
    name or address was given. ``config``: another config file than the user's. When
    a running agent of this user holds the controller, the requests go through its one
    connection (:attr:`Connection.via_agent`); ``direct``: a session of its own.

    Raises :class:`~rac_console.Refused` for a target, a port or a config file that
    cannot be used, :class:`~rac_console.ConnectionFailed` when the controller cannot be
    reached."""
    seconds = check_timeout(timeout)
    resolved = resolve(target, port, bool(read_only), loaded(config))
    session, simulator = open_session(resolved, seconds, bool(direct))
    return Connection(resolved, session, simulator, confirm=confirm, yes=yes)


class Connection:
    """One controller: :meth:`get`, :meth:`put`, :meth:`send`, :meth:`watch`. A context
    manager; :meth:`close` ends the session (and the built-in simulator it started)."""

    def __init__(
        self,
        target: Target,
        session: Session,
        simulator: SimulatorThread | None = None,
        *,
        confirm: Confirm | None = None,
        yes: bool = False,
    ) -> None:
        self._target = target
        self._session = session
        self._simulator = simulator
        self._at = Endpoint(session.host, session.port, session.timeout)
        self._lock = threading.RLock()  # RLock: a confirm callback may read again
        self._closed = False
        asking = _asking(confirm) if confirm is not None else None
        self._gate = WriteGate.for_library(target, confirm=asking, yes=yes)

    # ------------------------------------------------------------ what it is

    @property
    def host(self) -> str:
        """The address the session connects to (the simulator's, for ``"sim"``)."""
        return self._at.host

    @property
    def port(self) -> int:
        return self._at.port

    @property
    def profile(self) -> str | None:
        """The config profile shown for this controller, or None."""
        return self._target.profile.name if self._target.profile is not None else None

    @property
    def via_agent(self) -> bool:
        """Whether the requests go through a running agent's connection (it holds the
        controller; it went away: False from then on)."""
        return bool(getattr(self._session, "via_agent", False))

    @property
    def writes(self) -> Literal["open", "confirm", "read-only"]:
        """What the controller's rules let be written, as the console's status line says."""
        return self._target.writes

    def __repr__(self) -> str:
        name = f" profile {self.profile}" if self.profile else ""
        state = "closed" if self._closed else self.writes
        via = ", via agent" if self.via_agent and not self._closed else ""
        return f"<rac.Connection {self.host}:{self.port}{name} ({state}{via})>"

    # ------------------------------------------------------------ requests

    @overload
    def get(self, kind: Literal["I", "i"], index: int) -> int: ...
    @overload
    def get(self, kind: Literal["F", "f", "D", "d"], index: int) -> float: ...
    @overload
    def get(self, kind: Literal["S", "s"], index: int) -> str: ...
    @overload
    def get(self, kind: Literal["IO", "io", "Io", "iO"], index: int) -> bool: ...
    @overload
    def get(
        self, kind: Literal["V", "v", "P", "p", "J", "j", "T", "t"], index: int
    ) -> tuple[float, ...]: ...
    @overload
    def get(self, kind: str, index: int) -> Value: ...
    def get(self, kind: str, index: int) -> Value:
        """The value of one variable: ``get("I", 10)``; I int, F and D float, S str,
        IO bool, V, P, J and T a tuple of floats."""
        var = variable(kind, index)
        return value_of(self._exchange(Get(var)), var, self._at)

    def put(self, kind: str, index: int, value: Value, *, verify: bool = True) -> Written:
        """Write one variable as the console does, refused before anything goes out when
        the rules or the value say no; the value before and the read-back (``verify``
        False: none) in the :class:`Written`."""
        var = variable(kind, index)
        command = put_command(var, value)
        outcome = self._exchange(command, verify=verify)
        return written_of(outcome, var, value, self._at)

    def send(self, line: str) -> Sent:
        """A raw RAC line (``"GET:RC8:10:I:"``); one that may write goes by the same rules
        as :meth:`put`, read back as the console reads it back."""
        if not isinstance(line, str) or not line:
            raise Refused("send needs the text to send: send('GET:RC8:10:I:')")
        try:
            command = Raw.of(line)
        except InputError as exc:
            raise Refused(f"{exc} (nothing was sent)") from None
        return sent_of(self._exchange(command), command, self._at)

    def _answer(self, command: Exchange, outcome: Outcome) -> Value | Written | Sent:
        """What came of a command of the console's language (a cell's line), as the
        method that sends it says it: a get's value, a put's :class:`Written`, a raw
        line's :class:`Sent`; the exception for a failure."""
        if isinstance(command, Get):
            return value_of(outcome, command.var, self._at)
        if isinstance(command, Put):
            value = python_value(command.var.kind, command.value)
            return written_of(outcome, command.var, value, self._at)
        return sent_of(outcome, command, self._at)

    def watch(self, *variables: str, every: float = EVERY) -> Iterator[Reading]:
        """Each variable read every ``every`` seconds, as the console's ``watch`` names
        them (``"I 10"``, ``"IO 128-135"``, ``"P[0]"``): a :class:`Reading` per
        variable per cycle, a failed read one with its error. It runs until the caller
        stops iterating (``break``) or closes the connection."""
        watched = watch_list(variables)
        period = watch_period(every)
        return self._watching(watched, period)

    def _watching(self, watched: tuple[VarRef, ...], period: float) -> Iterator[Reading]:
        due = time.monotonic()
        while True:
            yield from self._cycle(watched)
            due += period
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            else:  # late: the next cycle now, none caught up
                due = time.monotonic()

    def _cycle(self, watched: tuple[VarRef, ...]) -> list[Reading]:
        """One read of each variable (a controller that cannot be reached is tried once a
        cycle: the rest of the cycle says why, unread)."""
        readings: list[Reading] = []
        down: str | None = None
        for var in watched:
            if down is not None:
                readings.append(Reading(str(var), None, time.time(), down))
                continue
            outcome = self._exchange(Get(var))
            now, variant = time.time(), outcome.variant
            if outcome.ok and variant is not None:
                readings.append(Reading(str(var), python_value(var.kind, variant), now))
                continue
            error = outcome.error or outcome.summary()
            readings.append(Reading(str(var), None, now, error))
            if isinstance(outcome.failure, ConnectFailed):
                down = f"not read: {error}"
        return readings

    def _exchange(self, command: Exchange, *, verify: bool = True) -> Outcome:
        """The one place a command meets the controller: through the console's write gate
        (:class:`rac_console.engine.exchange.gate.WriteGate`) under this connection's
        rules, one request at a time. Refused once the connection is closed."""
        gate = self._gate if verify else self._gate.without_read_back()
        with self._lock:
            if self._closed:
                raise Refused("the connection is closed: nothing was sent (connect again)")
            return gate.exchange(self._session, command)

    # ------------------------------------------------------------ the end

    def close(self) -> None:
        """End the session (and the simulator it started); later requests are Refused."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self._session.close()
        if self._simulator is not None:
            self._simulator.stop()

    def __enter__(self) -> Connection:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def watch_list(variables: tuple[str, ...]) -> tuple[VarRef, ...]:
    """The variables of ``watch("I 10", "IO 128-135")``, read by the console's parser."""
    if not variables:
        raise Refused("watch needs a variable: watch('I 10', 'IO 128-135')")
    found: list[VarRef] = []
    for text in variables:
        if not isinstance(text, str):
            raise Refused(f"watch takes variables as text such as 'I 10', got {text!r}")
        try:
            read, rest, _ = parse_var_list(text, WATCH_USAGE)
        except InputError as exc:
            raise Refused(str(exc)) from None
        if rest.strip():
            raise Refused(f"watch takes variables only, not {rest.strip()!r}: watch('I 10')")
        found += read
    return tuple(dict.fromkeys(found))


def watch_period(every: float) -> float:
    """``every`` in seconds, as the console's ``watch ... every`` takes it."""
    if isinstance(every, bool) or not isinstance(every, int | float):
        raise Refused(f"every is a number of seconds, got {every!r}")
    try:
        return parse_seconds(repr(float(every)), "every")
    except InputError as exc:
        raise Refused(str(exc)) from None


def _asking(confirm: Confirm) -> Callable[[VarRef, Variant | None, Variant, Put | Raw], bool]:
    """The console's question put to a script's ``confirm``: the variable, its value now
    and the value to write, as Python values."""

    def ask(var: VarRef, now: Variant | None, value: Variant, command: Put | Raw) -> bool:
        def python(variant: Variant) -> Value | None:
            fits = var.kind.reply_problem(variant) is None
            return python_value(var.kind, variant) if fits else plain_value(variant)

        written = python(value)
        return bool(
            confirm(
                str(var), None if now is None else python(now), "" if written is None else written
            )
        )

    return ask
