"""A front end's engine when an agent holds its target: the engine runs in the agent,
this stands in for it (the same calls as :class:`~rac_console.engine.Engine`), and what
the agent's engine publishes comes into this one's outbox as if it were made here.

If the agent goes away, this says so in one line and goes on with an engine of its own
(its own session), watching what was watched; a line the agent had not answered is
answered here: a write's outcome unknown, never sent again.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import asdict, replace
from typing import TYPE_CHECKING, Any

from ..commands.target import Target
from ..engine import Engine, EngineOptions, Outbox
from ..engine.setup.where import Where
from . import endpoint as endpoints
from .hellos import greet_agent
from .lines import may_write
from .server import CLIENT_OPTIONS
from .wire import Channel, ChannelClosed, Message, greet

if TYPE_CHECKING:
    from ..commands.language import Command, VarRef
    from ..commands.policy import TargetProfile
    from ..engine import Result, RowView
    from ..engine.commands.registry import Registry
    from ..session import Frame

#: On the status line while the engine runs in the agent.
VIA = "via agent"
#: The target on the status line when it is the agent's built-in simulator.
AGENT_SIMULATOR = "SIMULATOR (the agent's)"
#: Said when the agent went away and this front end goes on by itself.
AGENT_GONE = "the agent stopped: going on with a session of our own to {target}"
#: Said instead when the target was the agent's built-in simulator (gone with it).
AGENT_SIMULATOR_GONE = (
    "the agent stopped, and its simulator with it: going on with a simulator of our own, "
    "whose values start afresh (what was written is gone)"
)
#: The answer to a line the agent took and never answered.
UNANSWERED = (
    "the agent stopped before this line was answered: its outcome is unknown "
    "(a write may have reached the controller; it is not sent again)"
)


#: Said in the frame log when the agent left poll frames out (at most this often, s).
LEFT_OUT_EVERY = 30.0
LEFT_OUT = "{count:,} poll frames in {seconds:.0f} s not sent by the agent ({rate:,}/s at most)"


class Refused(Exception):
    """The agent turned this client away (another release): said in one line."""


def attach(
    target: Target,
    options: EngineOptions,
    *,
    client: str,
    where: Where,
    outbox: Outbox | None = None,
    numbers: Iterator[int] | None = None,
) -> RemoteEngine | None:
    """An engine through the running agent that holds ``target``; None when no agent
    runs, or it does not hold that target. :class:`Refused` when it turns us away."""
    given = asdict(options)
    greeted = greet_agent(
        target,
        client,
        where=where.value,
        options={k: _absolute(k, given[k]) for k in CLIENT_OPTIONS},
        bounds=given["bounds"],  # a served console's, from serve: kept at the agent
    )
    if greeted is None:
        return None
    channel, answer = greeted
    if answer.get("op") == "refused":
        channel.close()
        raise Refused(str(answer.get("why")))
    if answer.get("op") != "welcome":
        channel.close()
        return None
    engine = RemoteEngine(channel, answer, target, options, where, outbox)
    if numbers is not None:
        engine.numbers = numbers
    return engine


#: The options that name a file: the agent opens them, in its own working folder.
_FILES = ("record", "transcript", "log_csv")


def _absolute(name: str, value: object) -> object:
    """A file named relative to the client's folder, as the agent must open it."""
    if name in _FILES and isinstance(value, str):
        return os.path.abspath(os.path.expanduser(value))
    return value


def agent_status() -> Message | None:
    """What the running agent says of itself (``agent status``), or None."""
    reached = endpoints.reach()
    if reached is None:
        return None
    sock, endpoint = reached
    channel = Channel(sock)
    answer = greet(channel, endpoint.token, want="status")
    channel.close()
    return answer


class RemoteEngine:
    """Start it, submit lines, drain :attr:`outbox`, stop it: as an Engine."""

    def __init__(
        self,
        channel: Channel,
        welcome: Message,
        target: Target,
        options: EngineOptions,
        where: Where,
        outbox: Outbox | None,
    ) -> None:
        self._channel = channel
        self.name = str(welcome.get("client", "client"))
        self._rules = target
        self.options = options
        self.where = where
        self.outbox = outbox if outbox is not None else Outbox()
        self.numbers: Iterator[int] = itertools.count(1)
        self._registry: Registry | None = None
        self._then: dict[int, tuple[Callable[[Result], None] | None, bool]] = {}
        #: Submitted, not answered: the line as shown, and whether it may write.
        self._pending: dict[int, tuple[str | None, bool]] = {}
        self._lock = threading.Lock()
        self._observers: list[Callable[[Frame], None]] = []
        self._rows: dict[VarRef, RowView] = {}  # what the agent's engine watches
        self._local: Engine | None = None  # after the agent went away
        self._stopping = False
        self.died: str | None = None
        #: The agent went away (its channel closed): a line submitted from then on never
        #: reached it, and waits here (:attr:`_held`) for our own engine.
        self._gone = False
        self._held: list[
            tuple[str | Command, str | None, int, Callable[[Result], None] | None, bool]
        ] = []
        self._left_out = 0  # poll frames the agent left out, not said yet
        self._left_out_since: float | None = None  # since when
        self._left_out_said = -LEFT_OUT_EVERY  # when they were last said
        self._poll_frame_rate = int(welcome.get("poll_frames_per_second") or 0)
        self._reader = threading.Thread(target=self._read, name="rac-agent-client", daemon=True)

    # ------------------------------------------------------------ as an Engine

    @property
    def registry(self) -> Registry:
        if self._registry is None:
            from ..engine.commands.builtin import BUILTIN

            self._registry = BUILTIN
        return self._registry

    @property
    def target(self) -> Target:
        return self._rules

    @property
    def profiles(self) -> Mapping[str, TargetProfile]:
        return self._rules.profiles

    @property
    def ended(self) -> bool:
        return self._local.ended if self._local is not None else False

    def start(self, connect: bool = True) -> None:
        self._reader.start()

    def submit(self, line: str) -> int:
        return self._submit(line, line, None, None, True)

    def submit_command(
        self,
        command: Command | str,
        line: str | None = None,
        seq: int | None = None,
        then: Callable[[Result], None] | None = None,
        publish: bool = True,
    ) -> int:
        return self._submit(command, line, seq, then, publish)

    def _submit(
        self,
        what: str | Command,
        line: str | None,
        seq: int | None,
        then: Callable[[Result], None] | None,
        publish: bool,
    ) -> int:
        writes = may_write(self.registry, what)
        with self._lock:  # the agent's, or (once it went) our own: never neither
            local = self._local
            if local is None:
                number = next(self.numbers) if seq is None else seq
                if self._gone:  # the agent went: held for our own engine, never lost
                    self._held.append((what, line, number, then, publish))
                    return number
                self._then[number] = (then, publish)
                self._pending[number] = (line, writes)
                self._send({"op": "line", "seq": number, "what": what, "line": line})
                return number
        return local.submit_command(what, line, seq, then, publish)

    def stop(self, timeout: float = 5.0) -> None:
        with self._lock:  # an engine of our own made meanwhile sees it and stops
            self._stopping = True
            local = self._local
        if local is not None:
            local.stop(timeout)
        self._send({"op": "bye"})
        self._channel.close()
        self._reader.join(timeout)

    def cancel(self, queued: bool = False) -> None:
        if self._local is not None:
            self._local.cancel(queued)
        else:
            self._send({"op": "cancel", "queued": queued})

    def answer_confirm(self, seq: int, yes: bool) -> None:
        if self._local is not None:
            self._local.answer_confirm(seq, yes)
        else:
            self._send({"op": "answer", "seq": seq, "yes": yes})

    def set_poll_frames(self, shown: bool) -> None:
        self._poll_frames = shown
        if self._local is not None:
            self._local.set_poll_frames(shown)
        else:
            self._send({"op": "poll_frames", "shown": shown})

    def add_frame_observer(self, observer: Callable[[Frame], None]) -> None:
        self._observers.append(observer)

    def alert(self, text: str) -> None:
        from ..engine import Alert

        self.outbox.put(Alert(text))

    def publish_target(self) -> None:
        """Nothing to publish ahead: the agent's engine is up, its status comes first."""

    # ------------------------------------------------------------ from the agent

    def _send(self, message: Message) -> None:
        with contextlib.suppress(ChannelClosed):  # the reader finds out, goes on alone
            self._channel.send(message)

    def _read(self) -> None:
        try:
            for message in self._channel.messages():
                if message["op"] == "batch":
                    self._take(message)
        except ChannelClosed:
            pass
        except Exception:  # a batch of no use: as if the agent went away
            self._channel.close()
        with self._lock:  # lines from now on wait for our own engine
            self._gone = True
        if not self._stopping:
            self._go_alone()

    def _take(self, message: Message) -> None:
        from ..engine import Result
        from ..session import Frame

        events: list[Any] = []
        for event in message["events"]:
            if isinstance(event, Frame):
                for observer in self._observers:
                    observer(event)
            if isinstance(event, Result):
                with self._lock:
                    then, publish = self._then.pop(event.seq, (None, True))
                    self._pending.pop(event.seq, None)
                if then is not None:
                    then(event)
                if not publish:
                    continue
            events.append(event)
        outbox = self.outbox
        for var in message["removed"]:
            self._rows.pop(var, None)
        self._rows.update(message["rows"])
        outbox.put_many(events, message["rows"])
        if message["removed"]:
            outbox.put_removed(list(message["removed"]))
        status = message["status"]
        if status is not None:
            if self._rules.host is None:  # the agent's built-in simulator
                status = replace(status, target=AGENT_SIMULATOR, is_simulator=True)
            outbox.put_status(replace(status, via=VIA))
        self._say_left_out(int(message.get("polls_left_out") or 0))
        dropped = message["frames_dropped"], message["cycles_dropped"]
        if any(dropped):
            outbox.put_dropped(*dropped)

    def _say_left_out(self, count: int) -> None:
        """Poll frames the agent left out (see ``PollFrameBudget``): counted, and said in
        the frame log at most once every :data:`LEFT_OUT_EVERY` seconds."""
        from ..engine import Note

        now = time.monotonic()
        if count:
            if self._left_out_since is None:
                self._left_out_since = now
            self._left_out += count
        since = self._left_out_since
        if since is not None and now - self._left_out_said >= LEFT_OUT_EVERY:
            text = LEFT_OUT.format(
                count=self._left_out, seconds=max(now - since, 0.1), rate=self._poll_frame_rate
            )
            self.outbox.put(Note(text, time.time()))
            self._left_out, self._left_out_since, self._left_out_said = 0, None, now

    def _go_alone(self) -> None:
        """The agent went away: one line, then an engine of our own on the same
        outbox, watching what the agent's engine watched; unanswered lines answered."""
        from ..commands.language import Watch
        from ..commands.outcome import ExitStatus, Outcome
        from ..engine import Alert, Result

        gone = AGENT_SIMULATOR_GONE if self._rules.host is None else AGENT_GONE
        self.outbox.put(Alert(gone.format(target=self._target_text())))
        local = Engine(
            target=self._rules, options=self.options, outbox=self.outbox, where=self.where,
            numbers=self.numbers,
        )  # fmt: skip
        for observer in self._observers:
            local.add_frame_observer(observer)
        local.start()
        with self._lock:  # from here every line goes to our own engine
            stopped = self._stopping  # stopped while ours started: it goes too
            pending, self._pending = dict(self._pending), {}
            thens, self._then = dict(self._then), {}
            held, self._held = self._held, []
            if not stopped:
                self._local = local
        if stopped:
            local.stop()
            return
        for seq, (line, writes) in pending.items():
            unknown = Outcome(
                None, ExitStatus.TRANSPORT, error=UNANSWERED, input_line=line, write_unknown=writes
            )
            result = Result(seq, (unknown,), line, None)
            then, publish = thens.get(seq, (None, True))
            if then is not None:
                then(result)
            if publish:
                self.outbox.put(result)
        for row in self._rows.values():  # in the order they were added
            local.submit_command(Watch((row.var,), row.label, row.every), None, publish=False)
        for what, line, number, then, publish in held:  # typed after the agent went
            local.submit_command(what, line, number, then, publish)

    def _target_text(self) -> str:
        host = self._rules.host
        return "the built-in simulator" if host is None else f"{host}:{self._rules.port}"
