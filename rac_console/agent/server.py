"""The agent: one connection to each controller it holds, shared by every client.

Each client (a console, a REPL, a one-shot command, a served console, a script) gets an
engine of its own here, with the client's options and the strictest rules of the target
(the agent's profiles, and the client's ``--read-only``), whose session takes its turn
on the target's one connection (:mod:`rac_console.session.shared`). What the engine
publishes goes to the client as it drains it; a client that reads slowly gets the
latest rows and status and a count of the frames it missed, and never slows the polling
(the engine's outbox is bounded and only the client's own writer waits on it).
"""

from __future__ import annotations

import contextlib
import dataclasses
import hmac
import itertools
import os
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field

from ..commands.language import Raw
from ..commands.target import Target
from ..engine import Alert, Engine, EngineOptions, Outbox, Result
from ..engine.exchange.gate import rules_refusal
from ..engine.files.frame_files import FrameFiles
from ..engine.setup.where import Where
from ..protocol.request import Request
from ..session import Session
from ..session.shared import FrameBudget, SharedConnection, SharedSession
from ..session.types import Frame, NotSent, TransportError
from . import endpoint as endpoints
from .batches import POLL_FRAMES_PER_SECOND, send_batches
from .exporters import EXPORTER, Export, Exporters
from .hellos import client_kind, served_bounds
from .lines import may_write
from .wire import Channel, ChannelClosed, Message, hello_problem, proof

#: A client has this long to say hello.
HELLO_TIMEOUT = 5.0
#: The options a client may set on its engine, by name (anything else is the agent's).
CLIENT_OPTIONS = (
    "timeout",
    "interval",
    "verify",
    "cycles",
    "frames",
    "cut_cycles",
    "max_cycles",
    "readings",
    "record",
    "transcript",
    "log_csv",
)


@dataclass
class Held:
    """A controller the agent holds: its name, its rules, its one connection."""

    name: str
    target: Target
    connection: SharedConnection
    stop_simulator: Callable[[], None] | None = None

    @property
    def address(self) -> str:
        return f"{self.connection.host}:{self.connection.port}"


@dataclass
class Client:
    """One client attached: who, which target, its engine here."""

    number: int
    kind: str
    pid: int
    held: Held
    channel: Channel
    engine: Engine | None = None
    #: A script's connection (``rac.connect``): its requests on the shared connection.
    requests: SharedSession | None = None
    wake: threading.Event = field(default_factory=threading.Event)  # its engine published
    since: float = field(default_factory=time.time)
    missed: int = 0
    lines: int = 0  # lines received
    read_only: bool = False  # a script's connection started read_only=True
    budget: FrameBudget | None = None  # its poll frames a second (none: it keeps files)
    ending: bool = False

    @property
    def name(self) -> str:
        return f"{self.kind} {self.number}"


class Given:
    """An engine's job numbers as its client gave them (the client numbers its lines)."""

    def __init__(self) -> None:
        self.next = 0

    def __iter__(self) -> Iterator[int]:
        return self

    def __next__(self) -> int:
        return self.next


class Agent:
    """Holds ``targets`` (name, target) and serves clients until :meth:`stop`."""

    def __init__(
        self,
        targets: list[tuple[str, Target]],
        *,
        timeout: float = 2.0,
        say: Callable[[str], None] = print,
        simulators: dict[str, Callable[[], None]] | None = None,
    ) -> None:
        self.say = say
        self.timeout = timeout
        self.held: list[Held] = []
        for name, target in targets:
            assert target.host is not None
            session = Session(target.host, target.port, timeout=timeout)
            stop = (simulators or {}).get(name)
            self.held.append(Held(name, target, SharedConnection(session), stop))
        self.clients: dict[int, Client] = {}
        self._numbers = itertools.count(1)
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self._server: endpoints.Listener | None = None
        self.endpoint: endpoints.Endpoint | None = None
        self.started = time.time()
        self.exporters = Exporters(say)
        self._files: FrameFiles | None = None

    # ------------------------------------------------------------ its life

    def open(self) -> endpoints.Endpoint:
        """Listen (EndpointError when another agent runs), and connect to each target."""
        self._server, self.endpoint = endpoints.listen()
        for held in self.held:
            try:
                held.connection.session.connect()
                state = "connected"
            except OSError as exc:
                state = f"not connected yet: {exc}"
            except Exception as exc:  # a TransportError: said, and the clients retry
                state = f"not connected yet: {exc}"
            named = held.name if held.name == held.address else f"{held.name} ({held.address})"
            self.say(f"holding {named}: {state}")
        return self.endpoint

    def serve(self) -> None:
        """Accept clients until :meth:`stop` (on the calling thread)."""
        server = self._server
        assert server is not None
        while not self._stopping.is_set():
            try:
                channel = server.accept()
            except OSError:
                break
            if channel is not None:
                threading.Thread(target=self._serve_client, args=(channel,), daemon=True).start()

    def stop(self) -> None:
        """No new client; a request on the wire cut short (its client says how it
        went); every client ended at once, then the connections and the endpoint."""
        self._stopping.set()
        if self._server is not None:
            self._server.close()
        self.exporters.stop()
        for held in self.held:
            held.connection.session.interrupt()
        with self._lock:
            clients = list(self.clients.values())
        ending = [
            threading.Thread(target=self._end, args=(client, "the agent stopped"))
            for client in clients
        ]
        for thread in ending:
            thread.start()
        for thread in ending:
            thread.join(10)
        for held in self.held:
            held.connection.close()
            if held.stop_simulator is not None:
                held.stop_simulator()
        if self._files is not None:
            self._files.close()
        if self.endpoint is not None:
            endpoints.forget(self.endpoint)

    def keep_frames(self, files: FrameFiles) -> None:
        """The agent's own frame log (``--record``, ``--log``): every frame of each held
        connection, naming the client that asked (and the target, when several)."""
        self._files = files
        several = len(self.held) > 1
        for place, held in enumerate(self.held, 1):
            view = files.view(held.name, place) if several else files
            held.connection.record = view.frame

    def export(self, exports: Sequence[Export], options: EngineOptions) -> None:
        """Feed the plant (``--mqtt``, ``--metrics``, ``--log-csv``) from the targets
        held, whoever is attached: an engine of the agent's on each one's connection."""
        by_name = {held.name: held for held in self.held}
        self.exporters.start(
            exports,
            options,
            lambda name: _sessions_on(by_name[name], EXPORTER, _unseen, None),
            lambda name: by_name[name].target,
        )

    # ------------------------------------------------------------ one client

    def _serve_client(self, channel: Channel) -> None:
        unix = self.endpoint is not None and self.endpoint.path is not None
        if unix and not channel.peer_is_us():
            channel.close()
            return
        channel.set_timeout(HELLO_TIMEOUT)
        try:
            hello = channel.receive()
        except (ChannelClosed, TimeoutError, OSError):
            channel.close()
            return
        channel.set_timeout(None)
        try:
            client = self._welcome(channel, hello)
        except Exception:  # a hello with fields of the wrong kind
            client = None
        if client is None:
            channel.close()
            return
        why = "gone"
        try:
            for message in channel.messages():
                if not self._take(client, message):
                    break
        except ChannelClosed:
            pass
        except Exception as exc:  # a message of no use: the client goes, its engine too
            why = f"a message that cannot be taken: {type(exc).__name__}"
        finally:
            self._end(client, why)

    def _welcome(self, channel: Channel, hello: Message) -> Client | None:
        problem = hello_problem(hello)
        tcp = self.endpoint is not None and self.endpoint.port is not None
        token = self.endpoint.token if self.endpoint is not None else ""
        if problem is None and tcp and not hmac.compare_digest(str(hello.get("token", "")), token):
            problem = "the agent's token was not given"
        # Every answer proves the agent holds the token (a client on Windows checks it).
        signed = {"proof": proof(token, hello.get("nonce"))} if token else {}
        if problem is not None:
            self._send_quietly(channel, {"op": "refused", "why": problem, **signed})
            return None
        if hello.get("want") == "status":
            self._send_quietly(channel, {"op": "status", **self.status(), **signed})
            return None
        held = self._holding(hello.get("host"), hello.get("port"))
        if held is None:
            self._send_quietly(channel, {"op": "not_held"})
            return None
        client = Client(
            next(self._numbers), client_kind(hello.get("client")), int(hello.get("pid", 0)), held,
            channel,
        )  # fmt: skip
        if hello.get("want") == "requests":  # a script's connection: no engine of its own
            timeout = float(hello.get("timeout") or self.timeout)
            client.requests = held.connection.attach(client.name, _unseen, timeout)
            client.read_only = bool(hello.get("read_only"))
        else:
            try:
                client.engine = self._engine_for(client, hello)
            except Exception as exc:  # InputError: a file the client named cannot be opened
                self._send_quietly(channel, {"op": "refused", "why": str(exc)})
                return None
        with self._lock:
            self.clients[client.number] = client
        self._send_quietly(
            channel,
            {
                "op": "welcome",
                **signed,
                "client": client.name,
                "agent_pid": os.getpid(),
                "target": held.name,
                "address": held.address,
                "poll_frames_per_second": POLL_FRAMES_PER_SECOND,
            },
        )
        if client.engine is not None:
            threading.Thread(target=self._write_to, args=(client,), daemon=True).start()
            client.engine.start(connect=True)
        self.say(f"{client.name} (pid {client.pid}) attached to {held.name}")
        return client

    def _holding(self, host: object, port: object) -> Held | None:
        for held in self.held:
            if host is None and held.target.simulated and held.name == "sim":
                return held
            same_host = isinstance(host, str) and host.lower() == str(held.target.host).lower()
            if same_host and port == held.target.port:
                return held
        return None

    def _engine_for(self, client: Client, hello: Message) -> Engine:
        given = hello.get("options") or {}
        options = {k: given[k] for k in CLIENT_OPTIONS if k in given}
        held = client.held
        client_outbox = Outbox(notify=client.wake.set)
        if not (options.get("record") or options.get("transcript")):  # files want all
            client.budget = FrameBudget(POLL_FRAMES_PER_SECOND)
        session = _sessions_on(
            held, client.name, client_outbox.put, lambda text: client_outbox.put(Alert(text)),
            client.budget,
        )  # fmt: skip

        target = dataclasses.replace(
            held.target,
            read_only=held.target.read_only or bool(hello.get("read_only")),
            read_only_flag=bool(hello.get("read_only")),
        )
        where = Where(hello.get("where", Where.CONSOLE.value))
        engine_options = EngineOptions(
            **options, sessions=session, bounds=served_bounds(where, hello.get("bounds"))
        )
        engine = Engine(
            target=target, options=engine_options, outbox=client_outbox, where=where,
            numbers=Given(),
        )  # fmt: skip
        return engine

    def _take(self, client: Client, message: Message) -> bool:
        """One message from a client; False when it said goodbye."""
        op = message["op"]
        if op == "bye":
            return False
        if client.requests is not None:
            if op == "request":
                self._request(client, client.requests, message["request"])
            return True
        engine = client.engine
        assert engine is not None
        if op == "line":
            numbers = engine.numbers
            assert isinstance(numbers, Given)
            numbers.next = int(message["seq"])
            what, line = message["what"], message.get("line")
            order = client.held.connection.order
            ticket = order.take(client.name) if may_write(engine.registry, what) else None
            client.lines += 1

            def finished(result: Result, ticket: int | None = ticket) -> None:
                if ticket is not None:
                    order.done(ticket)

            engine.submit_command(what, line, numbers.next, then=finished)
        elif op == "answer":
            engine.answer_confirm(int(message["seq"]), bool(message["yes"]))
        elif op == "cancel":
            engine.cancel(bool(message.get("queued")))
        elif op == "poll_frames":
            engine.set_poll_frames(bool(message["shown"]))
        return True

    def _request(self, client: Client, session: SharedSession, request: object) -> None:
        """One request of a script's connection, answered before the next is read: sent
        in its turn (a write after every write received before it) unless the agent's
        rules for the target refuse it."""
        if not isinstance(request, Request):
            raise TypeError("a request that is no request")
        client.lines += 1
        held = client.held
        order = held.connection.order
        answer: Message
        refusal = None
        if not request.read_only_safe:
            read_only = held.target.read_only or client.read_only
            refusal = rules_refusal(held.target.policy, read_only, Raw.of(request.text))
        if refusal is not None:
            answer = {"op": "failed", "error": NotSent(f"at the agent: {refusal}")}
        else:
            ticket = None if request.read_only_safe else order.take(client.name)
            try:
                answer = {"op": "reply", "reply": session.exchange(request)}
            except TransportError as exc:
                answer = {"op": "failed", "error": exc}
            finally:
                if ticket is not None:
                    order.done(ticket)
        client.channel.send(answer)

    def _write_to(self, client: Client) -> None:
        """The client's batches, on a thread of its own (see :func:`.batches.send`)."""
        engine = client.engine
        assert engine is not None

        def missed(frames: int) -> None:
            client.missed += frames

        send_batches(
            engine.outbox, client.wake, client.channel, missed, POLL_FRAMES_PER_SECOND,
            client.budget,
        )  # fmt: skip

    def _end(self, client: Client, why: str) -> None:
        """The client is gone: its engine stops (its watches with it) before it leaves
        the list, so a client no longer listed polls nothing."""
        with self._lock:
            if client.ending:
                return
            client.ending = True
        if client.engine is not None:
            client.engine.stop()
        if client.requests is not None:
            client.requests.interrupt()
            client.requests.close()
        client.held.connection.order.done_all(client.name)
        client.channel.close()
        with self._lock:
            self.clients.pop(client.number, None)
        self.say(f"{client.name} detached ({why})")

    @staticmethod
    def _send_quietly(channel: Channel, message: Message) -> None:
        with contextlib.suppress(ChannelClosed):
            channel.send(message)

    # ------------------------------------------------------------ agent status

    def status(self) -> Message:
        """What ``agent status`` shows: the targets, their connections, the clients."""
        with self._lock:
            clients = list(self.clients.values())
        return {
            "pid": os.getpid(),
            "since": self.started,
            "endpoint": str(self.endpoint),
            "targets": [
                {
                    "name": held.name,
                    "address": held.address,
                    "state": held.connection.session.state,
                    "requests": held.connection.requests,
                    "shared_polls": held.connection.shared_polls,
                    "writes_waiting": held.connection.order.waiting,
                    "clients": sum(1 for c in clients if c.held is held),
                }
                for held in self.held
            ],
            "exporters": self.exporters.status(),
            "clients": [
                {
                    "name": c.name,
                    "pid": c.pid,
                    "target": c.held.name,
                    "since": c.since,
                    "missed": c.missed,
                    "lines": c.lines,
                }
                for c in clients
            ],
        }


def _unseen(frame: Frame) -> None:
    """A script's connection shows no frames: the other clients' are not sent to it."""


def _sessions_on(
    held: Held,
    name: str,
    foreign: Callable[[Frame], None],
    told: Callable[[str], None] | None,
    budget: FrameBudget | None = None,
) -> Callable[[str, int, float], Session]:
    """How the engine of ``name`` opens sessions: the held connection for the held
    address (``foreign`` takes the other clients' frames, ``told`` what the client is
    told at once); any other (``connect`` elsewhere, the built-in simulator) a session
    of the engine's own."""

    def session(host: str, port: int, timeout: float) -> Session:
        if (host, port) == (held.connection.host, held.connection.port):
            return held.connection.attach(name, foreign, timeout, told, budget)
        return Session(host, port, timeout=timeout)

    return session
