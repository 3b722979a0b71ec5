"""The OPC UA server's own process: the address space of the watched values.

``python -m rac_console.plant.opcua_space``, started by :class:`.opcua_server.OpcUaServer`
and spoken to over its stdin and stdout (msgpack messages, see :mod:`.opcua_pipe`). A
process of its own, with its own interpreter lock: a client that browses and subscribes
flat out costs this process, not the polls of the one that feeds it.

Address space: ``Objects/RacConsole/<target>/<variable>`` in the namespace
:data:`~..commands.opcua.NAMESPACE_URI`, NodeIds ``ns=N;s=<target>/<variable>``, each
variable with a ``Status`` property. A client's write is sent back to the feeding
process, whose engine holds the write gate; here it is only refused or passed on.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
import os
import sys
import threading
from dataclasses import dataclass
from typing import Any

from asyncua import Node, Server, ua
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.server.address_space import AttributeService

from ..commands.language import VarRef
from ..commands.opcua import NAMESPACE_URI, OpcUaAddress, OpcUaSettings, Security
from ..protocol import InputError, Variant, kind_of
from .opcua_pipe import FORGET, Pipe, Row
from .opcua_values import Served, data_value, initial_value, is_array, put_text, variant_type

#: Caps: connections (each a session at most), subscriptions and monitored items in
#: all. Past them a client is refused (BadTooMany...).
MAX_CONNECTIONS = 32
MAX_SUBSCRIPTIONS = 64
MAX_MONITORED_ITEMS = 20_000
#: A client's write waits at most this long for the engine's answer (BadTimeout then:
#: the write may still be applied; it is never sent again).
WRITE_DEADLINE = 30.0
ROOT = "RacConsole"
#: The key, beside a target's variables, of its polling paused or resumed.
PAUSED = "\x00paused"


@dataclass
class _Variable:
    node: Node
    status_node: Node
    status: str = ""
    served: Served | None = None  # the last value served


class Space:
    """The server and its address space, on this process's event loop."""

    def __init__(self, settings: OpcUaSettings, pipe: Pipe) -> None:
        self.settings = settings
        self.pipe = pipe
        self.server: Any = None
        self._ns = 0
        self._root: Node | None = None
        self._folders: dict[str, Node] = {}
        self._variables: dict[tuple[str, str], _Variable] = {}
        self.routes: dict[ua.NodeId, tuple[str, VarRef]] = {}
        self._pending: dict[tuple[str, str], Row | str | None] = {}
        self._wake = asyncio.Event()
        self.stopped = asyncio.Event()
        self._answers: dict[int, asyncio.Future[tuple[str, str]]] = {}
        self._paused: set[str] = set()  # the targets whose polling is paused
        self._numbers = itertools.count(1)

    def say(self, text: str, target: str | None = None) -> None:
        self.pipe.send(["say", text, target])

    # ------------------------------------------------------------ from the feeder

    def take(self, message: list[Any]) -> None:
        """A message from the feeding process (on the loop)."""
        word = message[0]
        if word == "rows":
            for target, key, row in message[1]:
                self._pending.pop((target, key), None)  # kept in the order of the news
                self._pending[(target, key)] = row
            self._wake.set()
        elif word == "answer":
            answer = self._answers.pop(message[1], None)
            if answer is not None and not answer.done():
                answer.set_result((message[2], message[3]))
        elif word == "paused":
            target, paused = message[1], message[2]
            (self._paused.add if paused else self._paused.discard)(target)
            self._pending.pop((target, PAUSED), None)
            self._pending[(target, PAUSED)] = None
            self._wake.set()
        elif word == "stop":
            self.stopped.set()

    # ------------------------------------------------------------ the server

    async def open(self) -> tuple[int, str | None, bool]:
        """Start serving; the port taken and the certificate (its path, made now)."""
        from .opcua_security import PasswordUsers, application_uri, secure

        settings = self.settings
        server = self.server = Server(
            user_manager=PasswordUsers(settings.username, settings.password)
        )
        await server.init()
        server.allow_remote_admin(False)
        server.set_server_name("rac-console")
        await server.set_application_uri(application_uri())
        host, port = settings.address.host, settings.address.port
        server.set_endpoint(f"opc.tcp://{f'[{host}]' if ':' in host else host}:{port}/")
        secured = await secure(server, settings, self.say)
        if secured is not None:
            from .opcua_channels import guard_channels

            guard_channels(settings, server.iserver.certificate_validator)
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
        if port == 0 and server.bserver is not None and server.bserver.port:
            port = server.bserver.port
        if secured is None:
            return port, None, False
        return port, str(secured[0]), secured[1]

    async def flush_forever(self) -> None:
        while True:
            await self._wake.wait()
            self._wake.clear()
            pending, self._pending = self._pending, {}
            for (target, key), row in pending.items():
                try:
                    await self._apply(target, key, row)
                except Exception as exc:  # one variable's trouble is not the others'
                    self.say(f"OPC UA: {target}/{key}: {exc}", target)

    async def _apply(self, target: str, key: str, row: Row | str | None) -> None:
        server = self.server
        if key == PAUSED:  # its polling paused or resumed: every value said again
            paused = target in self._paused
            for (owner, _), held in list(self._variables.items()):
                if owner == target and held.served is not None:
                    shown = data_value(held.served, paused)
                    await server.write_attribute_value(held.node.nodeid, shown)
            return
        if isinstance(row, str):  # the whole target
            await self._end_target(target, forget=row == FORGET)
            return
        variable = self._variables.get((target, key))
        if row is None:
            if variable is not None:
                del self._variables[(target, key)]
                self.routes.pop(variable.node.nodeid, None)
                await server.delete_nodes([variable.node], recursive=True)
            return
        code, index, label, value, status, stale, wall = row
        variant = Variant(0, value) if value is not None else None
        served = Served(VarRef(kind_of(code), index), label, variant, status, stale, wall)
        paused = target in self._paused
        if variable is None:
            variable = await self._make_variable(target, served, paused)  # its value first
        else:
            await server.write_attribute_value(variable.node.nodeid, data_value(served, paused))
        variable.served = served
        if status != variable.status:
            variable.status = status
            shown = ua.DataValue(ua.Variant(status, ua.VariantType.String))
            await server.write_attribute_value(variable.status_node.nodeid, shown)

    async def _end_target(self, target: str, forget: bool) -> None:
        keys = [key for key in self._variables if key[0] == target]
        if forget:
            for key in keys:
                self.routes.pop(self._variables.pop(key).node.nodeid, None)
            folder = self._folders.pop(target, None)
            if folder is not None:
                await self.server.delete_nodes([folder], recursive=True)
            return
        ended = ua.DataValue(
            ua.Variant(None, ua.VariantType.Null), ua.StatusCode(ua.StatusCodes.BadNoCommunication)
        )
        for key in keys:
            await self.server.write_attribute_value(self._variables[key].node.nodeid, ended)

    async def _make_variable(self, target: str, served: Served, paused: bool) -> _Variable:
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
        # Its first value before anything else: never a Good 0 to a client browsing now.
        await self.server.write_attribute_value(node_id, data_value(served, paused))
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
        self.routes[node_id] = (target, var)
        variable = _Variable(node, status_node)
        self._variables[(target, str(var))] = variable
        return variable

    # ------------------------------------------------------------ a client's write

    async def write(self, target: str, var: VarRef, value: ua.DataValue) -> ua.StatusCode:
        """A client's write to a watched variable: refused unless ``--opcua-writes``,
        else passed to the feeding process's engine; Good only when read back."""
        if not self.settings.writes:
            return ua.StatusCode(ua.StatusCodes.BadNotWritable)
        try:
            text = put_text(var.kind, value.Value.Value if value.Value is not None else None)
        except InputError as exc:
            self.say(f"OPC UA write to {target}/{var} refused: {exc}", target)
            return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
        number = next(self._numbers)
        answer: asyncio.Future[tuple[str, str]] = asyncio.get_running_loop().create_future()
        self._answers[number] = answer
        self.pipe.send(["write", number, target, var.kind.code, var.index, text])
        try:
            name, said = await asyncio.wait_for(answer, WRITE_DEADLINE)
        except TimeoutError:
            self._answers.pop(number, None)
            name, said = "BadTimeout", "no answer from the engine in time (it may be applied)"
        if name != "Good":
            self.say(f"OPC UA write to {target}/{var}: {name}: {said}", target)
        return ua.StatusCode(getattr(ua.StatusCodes, name, ua.StatusCodes.BadInternalError))


class GatedAttributes(AttributeService):  # type: ignore[misc]
    """asyncua's attribute service, but a client's write to a watched variable goes to
    :meth:`Space.write`; nothing else in the address space is writable by a client."""

    def __init__(self, aspace: Any, space: Space) -> None:
        super().__init__(aspace)
        self._space = space

    async def write(
        self, params: ua.WriteParameters, user: User | None = None
    ) -> list[ua.StatusCode]:
        if user is None or user.role == UserRole.Admin:  # the server's own session
            return list(await super().write(params, user or User(role=UserRole.Admin)))
        results: list[ua.StatusCode] = []
        for item in params.NodesToWrite:
            route = self._space.routes.get(item.NodeId)
            if route is None or item.AttributeId != ua.AttributeIds.Value:
                results.append(ua.StatusCode(ua.StatusCodes.BadNotWritable))
                continue
            results.append(await self._space.write(route[0], route[1], item.Value))
        return results


def _cap_monitored_items(service: Any) -> None:
    """At most MAX_MONITORED_ITEMS monitored items in all subscriptions (asyncua's
    subscriptions hold theirs in ``monitored_item_srv._monitored_items``)."""
    create = service.create_monitored_items

    async def capped(params: Any) -> list[Any]:
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


def settings_of(message: list[Any]) -> OpcUaSettings:
    host, port, security, writes, username, password = message[1:7]
    return OpcUaSettings(OpcUaAddress(host, port), Security(security), writes, username, password)


async def serve(pipe: Pipe) -> None:
    loop = asyncio.get_running_loop()
    first = await loop.run_in_executor(None, pipe.receive)
    if first is None or first[0] != "settings":
        return
    space = Space(settings_of(first), pipe)
    try:
        port, certificate, made = await space.open()
    except OSError as exc:
        where = space.settings.address
        pipe.send(["failed", f"--opcua {where}: cannot listen there: {exc.strerror or exc}"])
        return
    except Exception as exc:  # said in one line by the feeder, never a traceback
        pipe.send(["failed", f"the OPC UA server could not start: {exc}"])
        return

    def read() -> None:  # the feeder's messages, on a thread of their own
        while (message := pipe.receive()) is not None:
            loop.call_soon_threadsafe(space.take, message)
        loop.call_soon_threadsafe(space.stopped.set)  # the feeder has gone

    threading.Thread(target=read, name="rac-opcua-pipe", daemon=True).start()
    flusher = asyncio.create_task(space.flush_forever())
    pipe.send(["ready", port, certificate, made])
    try:
        await space.stopped.wait()
    finally:
        flusher.cancel()
        with contextlib.suppress(Exception):
            await space.server.stop()


def main() -> None:
    logging.disable(logging.CRITICAL)  # asyncua's words are not ours: nothing on stderr
    if hasattr(os, "nice"):
        with contextlib.suppress(OSError):
            os.nice(5)  # the polls of the feeding process come first
    pipe = Pipe(sys.stdin.buffer, sys.stdout.buffer)
    sys.stdout = sys.stderr  # nothing printed can break the messages
    with contextlib.suppress(KeyboardInterrupt, BrokenPipeError):
        asyncio.run(serve(pipe))


if __name__ == "__main__":
    main()
