"""The OPC UA server of ``--opcua``: the watched values, served to SCADA.

It runs on a thread of its own with its own event loop (asyncua). Engines hand it
their rows as they change (any thread, never waiting on a client): the latest of each
variable is kept and the server's loop takes them all at its next turn, so a client
that browses and subscribes flat out slows the server, not the polls.

Address space: ``Objects/RacConsole/<target>/<variable>`` in the namespace
:data:`~..commands.opcua.NAMESPACE_URI`, NodeIds ``ns=N;s=<target>/<variable>``. A
client's write reaches a controller only with ``--opcua-writes``, and then only
through the engine's write gate (see :mod:`..engine.polling.plant_writes`).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from asyncua import Node, Server, ua
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.server.address_space import AttributeService

from ..commands.language import VarRef
from ..commands.opcua import NAMESPACE_URI, OpcUaSettings
from ..protocol import InputError
from ..protocol.text import terminal_safe
from .opcua_values import Served, data_value, initial_value, is_array, put_text, variant_type

if TYPE_CHECKING:
    from collections.abc import Callable
    from concurrent.futures import Future

    from ..protocol import Variant


class PlantWrites(Protocol):
    """Where a target's writes go (the engine's, see engine/polling/plant_writes.py):
    the answer is an OPC UA status name and what was said."""

    def write(self, var: VarRef, text: str) -> Future[tuple[str, str]]: ...


class RowView(Protocol):
    """A watched row as an engine publishes it."""

    @property
    def var(self) -> VarRef: ...
    @property
    def label(self) -> str: ...
    @property
    def variant(self) -> Variant | None: ...
    @property
    def status(self) -> str: ...
    @property
    def stale(self) -> bool: ...


#: Caps: connections (each a session at most), subscriptions and monitored items in
#: all. Past them a client is refused (BadTooMany...), never served at the polls' cost.
MAX_CONNECTIONS = 32
MAX_SUBSCRIPTIONS = 64
MAX_MONITORED_ITEMS = 20_000
#: A client's write waits at most this long for the engine's answer (BadTimeout then:
#: the write may still be applied; it is never sent again).
WRITE_DEADLINE = 30.0
ROOT = "RacConsole"


@dataclass
class _Variable:
    node: Node
    status_node: Node
    status: str = ""


class OpcUaServer:
    """Start with :meth:`start` (InputError: it cannot listen); stop with :meth:`stop`."""

    def __init__(self, settings: OpcUaSettings) -> None:
        self.settings = settings
        self._lock = threading.Lock()
        #: The latest of each (target, variable) not yet served: None, unwatched; under
        #: (target, ""), the whole target: FORGET or ENDED.
        self._pending: dict[tuple[str, str], Served | str | None] = {}
        self._woken = False
        self._writers: dict[str, PlantWrites | None] = {}
        self._says: dict[str, Callable[[str], None]] = {}
        self._loop: asyncio.AbstractEventLoop | None = None
        self._wake: asyncio.Event | None = None
        self._stop: asyncio.Event | None = None
        self._ready = threading.Event()
        self._failure: str | None = None
        self._thread = threading.Thread(target=self._run, name="rac-opcua", daemon=True)
        self.port = settings.address.port
        self.certificate: str | None = None  # its path, when the server has one
        self.certificate_made = False  # made at this start
        # The loop's own (the address space as made).
        self._ns = 0
        self._root: Node | None = None
        self._folders: dict[str, Node] = {}
        self._variables: dict[tuple[str, str], _Variable] = {}
        self._routes: dict[ua.NodeId, tuple[str, VarRef]] = {}

    def __str__(self) -> str:
        host = self.settings.address.host
        shown = f"[{host}]" if ":" in host else host
        return f"opc.tcp://{shown}:{self.port}"

    # ------------------------------------------------------------ any thread

    def start(self) -> None:
        self._thread.start()
        self._ready.wait(60)
        if self._failure is not None or not self._ready.is_set():
            raise InputError(self._failure or f"the OPC UA server at {self} did not start")

    def stop(self) -> None:
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None and not loop.is_closed():
            try:
                loop.call_soon_threadsafe(stop.set)
            except RuntimeError:  # the loop has just closed
                return
            self._thread.join(10)

    def attach(self, target: str, writes: PlantWrites | None, say: Callable[[str], None]) -> None:
        """An engine serves ``target``'s values (and takes its writes); ``say`` tells
        its user what became of a client's write (any thread)."""
        with self._lock:
            self._writers[target] = writes
            self._says[target] = say

    def detach(self, target: str, forget: bool = False) -> None:
        """The engine of ``target`` ended: its values go Bad (``forget``: its folder goes,
        the engine now reading another target)."""
        with self._lock:
            self._writers.pop(target, None)
            self._says.pop(target, None)
            self._queue((target, ""), FORGET if forget else ENDED)
        self._kick()

    def update(self, target: str, views: Iterable[RowView], wall: float) -> None:
        """Rows whose value or health changed (the engine's thread)."""
        with self._lock:
            for view in views:
                served = Served(view.var, view.label, view.variant, view.status, view.stale, wall)
                self._queue((target, str(view.var)), served)
        self._kick()

    def remove(self, target: str, variables: Iterable[VarRef]) -> None:
        """Rows unwatched: their variables leave the address space."""
        with self._lock:
            for var in variables:
                self._queue((target, str(var)), None)
        self._kick()

    def _queue(self, key: tuple[str, str], what: Served | str | None) -> None:
        """Kept in the order of the last news of each (a value after its target ended
        is served after the end)."""
        self._pending.pop(key, None)
        self._pending[key] = what

    def _say(self, text: str, target: str | None = None) -> None:
        """Told to the user of ``target`` (else of the first target served)."""
        with self._lock:
            say = self._says.get(target or "") or next(iter(self._says.values()), None)
        if say is not None:
            say(text)

    def _kick(self) -> None:
        loop, wake = self._loop, self._wake
        with self._lock:
            if self._woken or loop is None or wake is None:
                return
            self._woken = True
        with contextlib.suppress(RuntimeError):  # the loop has stopped
            loop.call_soon_threadsafe(wake.set)

    # ------------------------------------------------------------ the server's loop

    def _run(self) -> None:
        logging.getLogger("asyncua").setLevel(logging.CRITICAL)  # its words are not ours
        try:
            asyncio.run(self._main())
        except Exception as exc:  # never a traceback: said, and the values no longer served
            if not self._ready.is_set():
                self._failure = f"the OPC UA server at {self} could not start: {exc}"
                self._ready.set()
            else:
                self._say(f"the OPC UA server at {self} stopped: {terminal_safe(str(exc))}")

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._wake, self._stop = asyncio.Event(), asyncio.Event()
        try:
            server = await self._open()
        except OSError as exc:
            why = exc.strerror or str(exc)
            self._failure = f"--opcua {self.settings.address}: cannot listen there: {why}"
            self._ready.set()
            return
        flusher = asyncio.create_task(self._flush_forever(server))
        self._ready.set()
        try:
            await self._stop.wait()
        finally:
            flusher.cancel()
            await server.stop()

    async def _open(self) -> Server:
        from .opcua_security import PasswordUsers, application_uri, secure

        settings = self.settings
        users = PasswordUsers(settings.username, settings.password)
        server = Server(user_manager=users)
        await server.init()
        server.allow_remote_admin(False)
        server.set_server_name("rac-console")
        await server.set_application_uri(application_uri())
        server.set_endpoint(f"opc.tcp://{_url_host(settings.address.host)}:{self.port}/")
        secured = await secure(server, settings, self._say)
        if secured is not None:
            self.certificate, self.certificate_made = str(secured[0]), secured[1]
        iserver = server.iserver
        iserver.max_connections = MAX_CONNECTIONS
        iserver.max_subscriptions = MAX_SUBSCRIPTIONS
        iserver.attribute_service = GatedAttributes(iserver.aspace, self)
        _cap_monitored_items(iserver.subscription_service)
        self._ns = await server.register_namespace(NAMESPACE_URI)
        objects = server.get_objects_node()
        self._root = await objects.add_folder(
            ua.NodeId(ROOT, self._ns), ua.QualifiedName(ROOT, self._ns)
        )
        await server.start()
        if self.port == 0 and server.bserver is not None and server.bserver.port:
            self.port = server.bserver.port
        return server

    async def _flush_forever(self, server: Server) -> None:
        assert self._wake is not None
        while True:
            await self._wake.wait()
            self._wake.clear()
            with self._lock:
                pending, self._pending = self._pending, {}
                self._woken = False
            for (target, key), served in pending.items():
                try:
                    await self._apply(server, target, key, served)
                except Exception as exc:  # one variable's trouble is not the others'
                    self._say(f"OPC UA: {target}/{key}: {terminal_safe(str(exc))}")

    async def _apply(
        self, server: Server, target: str, key: str, served: Served | str | None
    ) -> None:
        if isinstance(served, str):  # the whole target
            await self._end_target(server, target, forget=served == FORGET)
            return
        variable = self._variables.get((target, key))
        if served is None:
            if variable is not None:
                del self._variables[(target, key)]
                self._routes.pop(variable.node.nodeid, None)
                await server.delete_nodes([variable.node], recursive=True)
            return
        if variable is None:
            variable = await self._make_variable(target, served)
        await server.write_attribute_value(variable.node.nodeid, data_value(served))
        if served.status != variable.status:
            variable.status = served.status
            status = ua.DataValue(ua.Variant(served.status, ua.VariantType.String))
            await server.write_attribute_value(variable.status_node.nodeid, status)

    async def _end_target(self, server: Server, target: str, forget: bool) -> None:
        keys = [key for key in self._variables if key[0] == target]
        if forget:
            for key in keys:
                self._routes.pop(self._variables.pop(key).node.nodeid, None)
            folder = self._folders.pop(target, None)
            if folder is not None:
                await server.delete_nodes([folder], recursive=True)
            return
        ended = ua.DataValue(
            ua.Variant(None, ua.VariantType.Null), ua.StatusCode(ua.StatusCodes.BadNoCommunication)
        )
        for key in keys:
            await server.write_attribute_value(self._variables[key].node.nodeid, ended)

    async def _make_variable(self, target: str, served: Served) -> _Variable:
        ns, var = self._ns, served.var
        folder = self._folders.get(target)
        if folder is None:
            assert self._root is not None
            folder = await self._root.add_folder(
                ua.NodeId(target, ns), ua.QualifiedName(target, ns)
            )
            self._folders[target] = folder
        kind = var.kind
        node_id = ua.NodeId(f"{target}/{var}", ns)
        node = await folder.add_variable(
            node_id, ua.QualifiedName(str(var), ns), initial_value(kind), variant_type(kind)
        )
        if is_array(kind):
            await node.write_value_rank(1)
            await node.write_array_dimensions([kind.count])
        shown = served.label or str(var)
        await node.write_attribute(
            ua.AttributeIds.DisplayName, ua.DataValue(ua.Variant(ua.LocalizedText(shown)))
        )
        about = f"{served.label} ({var}, {kind.title})" if served.label else f"{var}: {kind.title}"
        await node.write_attribute(
            ua.AttributeIds.Description, ua.DataValue(ua.Variant(ua.LocalizedText(about)))
        )
        if self.settings.writes:
            await node.set_writable()
        status_node = await node.add_property(
            ua.NodeId(f"{target}/{var}/Status", ns), ua.QualifiedName("Status", ns), "WAITING"
        )
        self._routes[node_id] = (target, var)
        variable = _Variable(node, status_node)
        self._variables[(target, str(var))] = variable
        return variable

    # ------------------------------------------------------------ a client's write

    async def write(self, target: str, var: VarRef, value: ua.DataValue) -> ua.StatusCode:
        """A client's write to a watched variable: refused unless ``--opcua-writes``,
        else through the engine's write gate; Good only when read back as written."""
        if not self.settings.writes:
            return ua.StatusCode(ua.StatusCodes.BadNotWritable)
        with self._lock:
            writes = self._writers.get(target)
        if writes is None:
            return ua.StatusCode(ua.StatusCodes.BadNotWritable)
        try:
            text = put_text(var.kind, value.Value.Value if value.Value is not None else None)
        except InputError as exc:
            self._say(f"OPC UA write to {target}/{var} refused: {exc}", target)
            return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
        answer = asyncio.wrap_future(writes.write(var, text))
        try:
            name, said = await asyncio.wait_for(answer, WRITE_DEADLINE)
        except TimeoutError:
            name, said = "BadTimeout", "no answer from the engine in time"
        if name != "Good":
            self._say(f"OPC UA write to {target}/{var}: {name}: {terminal_safe(said)}", target)
        return ua.StatusCode(getattr(ua.StatusCodes, name))


#: A target's engine ended: its values go Bad, its folder stays; or its folder goes.
ENDED, FORGET = "ended", "forget"


class GatedAttributes(AttributeService):  # type: ignore[misc]
    """asyncua's attribute service, but a write to a watched variable goes to
    :meth:`OpcUaServer.write`; nothing else in the address space is writable."""

    def __init__(self, aspace: Any, owner: OpcUaServer) -> None:
        super().__init__(aspace)
        self._owner = owner

    async def write(
        self, params: ua.WriteParameters, user: User | None = None
    ) -> list[ua.StatusCode]:
        if user is None or user.role == UserRole.Admin:  # the server's own session
            return list(await super().write(params, user or User(role=UserRole.Admin)))
        results: list[ua.StatusCode] = []
        for item in params.NodesToWrite:
            route = self._owner._routes.get(item.NodeId)
            if route is None or item.AttributeId != ua.AttributeIds.Value:
                results.append(ua.StatusCode(ua.StatusCodes.BadNotWritable))
                continue
            results.append(await self._owner.write(route[0], route[1], item.Value))
        return results


def _cap_monitored_items(service: Any) -> None:
    """At most MAX_MONITORED_ITEMS monitored items in all subscriptions."""
    create = service.create_monitored_items

    async def capped(
        params: ua.CreateMonitoredItemsParameters,
    ) -> list[ua.MonitoredItemCreateResult]:
        held = sum(
            len(sub.monitored_item_srv._monitored_items) for sub in service.subscriptions.values()
        )
        asked = list(params.ItemsToCreate)
        room = max(MAX_MONITORED_ITEMS - held, 0)
        if len(asked) <= room:
            return list(await create(params))
        params.ItemsToCreate = asked[:room]
        made = list(await create(params)) if room else []
        refused = ua.MonitoredItemCreateResult()
        refused.StatusCode = ua.StatusCode(ua.StatusCodes.BadTooManyMonitoredItems)
        return made + [refused] * (len(asked) - room)

    service.create_monitored_items = capped


def _url_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host
