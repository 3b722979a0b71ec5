"""The interactive console's engine, shared by the Textual app and the REPL.

It owns the target (a controller or the in-process simulator), the one session,
the watch list and its poller, and turns each typed line into feedback. It
never draws anything: front ends read its state and listen to its log events.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Callable
from dataclasses import dataclass

from .backoff import Backoff
from .client import (
    PRIORITY_POLL,
    BadReply,
    ConnectFailed,
    Disconnected,
    Frame,
    RacSession,
    RequestTimeout,
    State,
    TransportError,
)
from .commands.language import (
    Connect,
    Frames,
    Get,
    Help,
    Latency,
    Put,
    Raw,
    SetInterval,
    Simple,
    Unwatch,
    Watch,
    WatchFile,
    parse_command,
)
from .commands.outcome import Outcome
from .commands.table import help_lines
from .execute import execute, measure_latency
from .protocol import InputError, describe_hresult, hresult_name
from .recorder import FrameRecorder
from .sim.server import SimulatorServer
from .watch import WatchList, WatchRow

DEFAULT_INTERVAL = 0.5
SIMULATOR_NOTICE = "no -H given: talking to the built-in RC8 simulator, not a controller"


@dataclass(frozen=True)
class Message:
    """Feedback that is not an exchange: help text, a confirmation, an error."""

    text: str
    level: str = "info"  # info, error


@dataclass(frozen=True)
class Action:
    """Something only the front end can do: ``clear`` its log, ``quit``, ``frames``."""

    name: str
    on: bool = True


@dataclass(frozen=True)
class Alert:
    """Something to tell the user at once, whatever they are doing: a recording stopped."""

    text: str


Feedback = Outcome | Message | Action
LogEvent = Frame | str | Alert  # a frame, a note such as a connection gap, or an alert
LogListener = Callable[[LogEvent], None]


class ConsoleCore:
    def __init__(
        self,
        host: str | None = None,
        port: int = 5006,
        *,
        timeout: float = 2.0,
        read_only: bool = False,
        record: str | None = None,
        interval: float = DEFAULT_INTERVAL,
    ) -> None:
        self.host, self.port, self.timeout = host, port, timeout
        self.read_only = read_only
        self.interval = interval
        self.watch = WatchList()
        self.seen: set[tuple[str, int]] = set()
        self.paused = False
        self.session: RacSession | None = None
        self.simulator: SimulatorServer | None = None
        self.connection: State | str = "closed"
        self.retry_at: float | None = None
        self.cycle_seconds: float | None = None
        self.polls_per_second: float | None = None
        self.polls = 0
        self._listeners: list[LogListener] = []
        self._recorder = FrameRecorder(record, self._alert) if record else None
        self._wake = asyncio.Event()
        self._poll_task: asyncio.Task[None] | None = None
        self._lost = False
        self.backoff = Backoff()
        self._early_drop = False

    # ------------------------------------------------------------ lifecycle

    async def start(self) -> None:
        await self._open_target(self.host, self.port)
        self._poll_task = asyncio.get_running_loop().create_task(self._poll_forever())

    async def stop(self) -> None:
        if self._poll_task is not None:
            self._poll_task.cancel()
            await asyncio.gather(self._poll_task, return_exceptions=True)
            self._poll_task = None
        await self._close_target()
        if self._recorder is not None:
            self._recorder.close()

    async def _open_target(self, host: str | None, port: int) -> None:
        if host is None:
            self.simulator = await SimulatorServer().start()
            host, port = self.simulator.host, self.simulator.port
        self.host, self.port = host, port
        self.backoff, self._early_drop = Backoff(), False  # a new target starts afresh
        session = RacSession(host, port, timeout=self.timeout)
        session.add_frame_observer(self._on_frame)
        session.add_state_observer(self._on_state)
        self.session = session
        self._wake.set()

    async def _close_target(self) -> None:
        if self.session is not None:
            await self.session.close()
            self.session = None
        if self.simulator is not None:
            await self.simulator.stop()
            self.simulator = None
        self.connection = "closed"

    @property
    def is_simulator(self) -> bool:
        return self.simulator is not None

    @property
    def target(self) -> str:
        if self.session is None:
            return "NOT CONNECTED"
        if self.is_simulator:
            return "SIMULATOR (built-in)"
        return f"LIVE {self.host}:{self.port}"

    # -------------------------------------------------------------- events

    def add_log_listener(self, listener: LogListener) -> None:
        self._listeners.append(listener)

    def _on_frame(self, frame: Frame) -> None:
        if self._recorder is not None:
            self._recorder(frame)
        for listener in self._listeners:
            listener(frame)

    def note(self, text: str) -> None:
        for listener in self._listeners:
            listener(text)

    def _alert(self, text: str) -> None:
        for listener in self._listeners:
            listener(Alert(text))

    def exit_status(self, status: int) -> int:
        """The console's exit status: 4 (a local I/O error) when it would be 0 but the
        recording stopped on the way."""
        return 4 if status == 0 and self.record_failure is not None else status

    @property
    def record_failure(self) -> str | None:
        """Why ``--record`` stopped, once it has."""
        return self._recorder.failure if self._recorder is not None else None

    def _on_state(self, state: State) -> None:
        self.connection = state
        if state != "connected":
            self._forget_figures()
        if state == "closed" and self.backoff.closed():
            self._early_drop = True  # the poller waits before its next request
        if state in ("connecting", "connected"):  # closed while connecting counts too
            self.backoff.connected()
            self.retry_at = None
            if self._lost:
                self._lost = False
                self.note(f"reconnected to {self.host}:{self.port}")

    def _forget_figures(self) -> None:
        """Round trips and poll rates measured on a connection that is gone say nothing now."""
        self.cycle_seconds = None
        self.polls_per_second = None
        if self.session is not None:
            self.session.last_rtt = None

    def mark_failure(self, error: TransportError) -> None:
        """One line in the log for each request that got no trustworthy reply."""
        if isinstance(error, ConnectFailed):
            return  # an outage is marked once, by the poller or the command's own result
        if isinstance(error, Disconnected):
            self.note(f"{error}: the next request reconnects")
        else:
            self.note(f"{error}: session reset")

    # ------------------------------------------------------------ commands

    async def handle_line(self, line: str) -> list[Feedback]:
        """Run one typed line; every problem becomes feedback, never an exception."""
        try:
            command = parse_command(line)
        except InputError as exc:
            return [Message(str(exc), "error")]
        if command is None:
            return []
        if isinstance(command, Get | Put | Raw):
            if self.session is None:
                return [Message("not connected: connect HOST[:PORT] first", "error")]
            if isinstance(command, Get | Put):
                self.seen.add((command.var.kind.code, command.var.index))
            outcome = await execute(self.session, command, read_only=self.read_only, line=line)
            if isinstance(outcome.failure, TransportError):
                self.mark_failure(outcome.failure)
            return [outcome]
        if isinstance(command, Frames):
            return [Action("frames", command.on)]
        if isinstance(command, Latency):
            if self.session is None:
                return [Message("not connected: connect HOST[:PORT] first", "error")]
            try:
                summary = await measure_latency(
                    self.session, command.var, command.count, command.interval
                )
            except ConnectFailed as exc:
                return [Message(str(exc), "error")]
            return [Message(summary.text(f"GET {command.var}"))]
        if isinstance(command, Watch):
            added = self.watch.add(command.vars, command.label, command.every)
            self.seen.update((v.kind.code, v.index) for v in command.vars)
            self._wake.set()
            names = _names(command.vars)
            text = f"watching {names}" if added else f"{names} already watched"
            if command.every is not None:
                text += (
                    f", polled every {command.every:g} s (other rows: interval {self.interval:g} s)"
                )
            return [Message(text)]
        if isinstance(command, Unwatch):
            return [self._unwatch(command)]
        if isinstance(command, SetInterval):
            self.interval = command.seconds
            self._wake.set()
            return [Message(f"poll interval {command.seconds:g} s")]
        if isinstance(command, Connect):
            return [await self.connect(command.host, command.port)]
        if isinstance(command, WatchFile):
            return [self._watch_file(command)]
        if isinstance(command, Help):
            return [Message("\n".join(help_lines(command.topic)))]
        return [await self._simple(command)]

    def _unwatch(self, command: Unwatch) -> Message:
        absent = [v for v in command.vars if v not in self.watch.rows]
        if command.vars and len(absent) == len(command.vars):
            return Message(f"{_names(command.vars)} not watched: nothing to stop", "error")
        removed = self.watch.remove(command.vars)
        text = f"stopped watching {removed} variable{'s' * (removed != 1)}"
        if absent:
            text += (
                f" ({_names(tuple(absent))} {'was' if len(absent) == 1 else 'were'} not watched)"
            )
        return Message(text)

    async def _simple(self, command: Simple) -> Feedback:
        name = command.name
        if name in ("pause", "resume"):
            self.set_paused(name == "pause")
            return Message("polling paused" if self.paused else "polling resumed")
        if name == "disconnect":
            await self._close_target()
            self.watch.mark_all("DISCONNECTED")
            self.note("disconnected")
            return Message("disconnected: connect HOST[:PORT] to talk to a controller")
        return Action(name)

    async def connect_now(self) -> Message | None:
        """Open the connection at start, so the status line tells the truth at once."""
        if self.session is None:
            return None
        try:
            await self.session.connect()
        except ConnectFailed as exc:
            return Message(f"{exc}: commands will retry", "error")
        return None

    def set_paused(self, paused: bool) -> None:
        self.paused = paused
        if paused:
            self.cycle_seconds = self.polls_per_second = None
        self._wake.set()

    async def connect(self, host: str, port: int) -> Message:
        await self._close_target()
        await self._open_target(host, port)
        assert self.session is not None
        try:
            await self.session.connect()
        except ConnectFailed as exc:
            return Message(f"{exc}; will keep retrying while variables are watched", "error")
        self.note(f"connected to {host}:{port}")
        return Message(f"connected to LIVE controller {host}:{port}")

    def _watch_file(self, command: WatchFile) -> Message:
        from . import watchlist

        try:
            if command.action == "save":
                saved = [(row.var, row.label, row.every) for row in self.watch.rows.values()]
                watchlist.save(command.path, saved)
                return Message(f"saved {len(saved)} watched variables to {command.path}")
            rows = watchlist.load(command.path)
        except InputError as exc:
            return Message(str(exc), "error")
        for var, label, every in rows:
            self.watch.add((var,), label, every)
            self.seen.add((var.kind.code, var.index))
        self._wake.set()
        return Message(f"loaded {len(rows)} watched variables from {command.path}")

    # -------------------------------------------------------------- polling

    async def _poll_forever(self) -> None:
        while True:
            if self.session is None or self.paused or not self.watch.rows:
                await self._wake.wait()
                self._wake.clear()
                continue
            started = time.perf_counter()
            try:
                count = await self._poll_cycle(self.session)
            except ConnectFailed as exc:
                if not self._lost:
                    self._lost = True
                    self.watch.mark_all("DISCONNECTED")
                    self.note(f"connection lost: {exc}")
                await self._wait_to_retry("lost")
                self._early_drop = False  # that failure has had its wait
                continue
            except Exception as exc:  # a bug must not silently stop the live table
                self.note(f"polling error: {exc!r}")
                await self._sleep(1.0)
                continue
            elapsed = time.perf_counter() - started
            if count:
                self.cycle_seconds = elapsed
            await self._sleep(self.period - elapsed)
            period = time.perf_counter() - started
            if count and period > 0:
                self.polls_per_second = count / period

    async def _wait_to_retry(self, state: str) -> None:
        """Back off before the next try; the status line counts it down, then shows
        the session's real state again (also when a pause or a new target cut it short)."""
        delay = self.backoff.next_delay()
        self.connection = state
        self.retry_at = time.monotonic() + delay
        try:
            await self._sleep(delay)
        finally:
            self.retry_at = None
            self.connection = self.session.state if self.session is not None else "closed"

    async def _sleep(self, seconds: float) -> None:
        """Wait, but wake early when the watch list, interval or target changes
        (also when that happened during the cycle that just ended)."""
        if seconds > 0:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._wake.wait(), seconds)
        else:
            await asyncio.sleep(0)
        self._wake.clear()

    async def _poll_cycle(self, session: RacSession) -> int:
        count = 0
        now = time.monotonic()
        for row in list(self.watch.rows.values()):
            if self.paused or session is not self.session:
                break
            if self.watch.rows.get(row.var) is not row:
                continue  # unwatched during the cycle
            if not row.due(now, self.interval):
                continue  # a row with its own, longer period
            if self._early_drop:
                # The last connection closed before it served a couple of exchanges: wait
                # here, then go on with this row (cutting the cycle would starve the rest).
                self._early_drop = False
                self.note(
                    f"the connection closed after {self.backoff.served} good "
                    f"exchange{'s' * (self.backoff.served != 1)}: waiting "
                    f"{self.backoff.delay:g} s before the next try"
                )
                await self._wait_to_retry("dropped")
                if self.paused or session is not self.session:
                    break
            await self._poll_row(session, row)
            count += 1
        return count

    async def _poll_row(self, session: RacSession, row: WatchRow) -> None:
        var = row.var
        try:
            reply = await session.get(var.kind, var.index, priority=PRIORITY_POLL)
        except ConnectFailed:
            raise
        except TransportError as exc:
            self.mark_failure(exc)
            status = {RequestTimeout: "TIMEOUT", BadReply: "BAD REPLY"}.get(type(exc))
            row.fail(status or "DISCONNECTED", time.monotonic())
            self.polls += 1
            self.watch.dirty.add(var)
            return
        else:
            response = reply.response
            self.backoff.good()
            if response.ok and response.variant is not None:
                row.update(response.variant, time.monotonic())
            else:
                row.fail(
                    hresult_name(response.code) or describe_hresult(response.code)[:10],
                    time.monotonic(),
                )
        self.polls += 1
        self.watch.dirty.add(var)

    @property
    def period(self) -> float:
        """Seconds between poll cycles: the interval, or a row's shorter ``every``."""
        return self.watch.period(self.interval)

    @property
    def interval_met(self) -> bool:
        """Period 0 asks for polls back to back: met by definition."""
        period = self.period
        if self.cycle_seconds is None or period == 0:
            return True
        return self.cycle_seconds <= period * 1.05 + 0.001


def _names(variables: tuple) -> str:
    """``IO4``, ``IO4..IO7 (4 variables)`` for a range, else ``P0, J0``."""
    if len(variables) == 1:
        return str(variables[0])
    first = variables[0]
    if all(v.kind == first.kind and v.index == first.index + n for n, v in enumerate(variables)):
        return f"{first}..{variables[-1]} ({len(variables)} variables)"
    if len(variables) <= 6:
        return ", ".join(str(v) for v in variables)
    return f"{', '.join(str(v) for v in variables[:5])} and {len(variables) - 5} more"
