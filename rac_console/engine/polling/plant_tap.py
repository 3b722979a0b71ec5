"""One engine's feed to the plant: its watched rows and its status, as they change.

Owned by the engine's thread, like the publisher that calls it. Nothing here waits on
the network: the MQTT feed takes the latest payload of a topic into a dict, the metrics
board takes numbers under a lock; their own threads do the rest. Nothing comes back
from the plant: no topic is subscribed to, so nothing received can reach a controller.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

from ...commands.language import VarRef
from ...commands.plant import Credentials, MqttAddress, topic_level
from ...protocol import InputError
from ...protocol.text import endpoint
from ..published.events import RowView
from ..published.status import WAITING, Status

#: The status a retained topic is left with when its variable is unwatched.
UNWATCHED = "UNWATCHED"

if TYPE_CHECKING:
    from ...commands.target import Target
    from ...plant.metrics import MetricsBoard
    from ...plant.mqtt import MqttFeed
    from ...plant.opcua_server import OpcUaServer
    from ..setup.options import EngineOptions
    from .plant_writes import PlantWrites, Submit


class PlantTap:
    """The MQTT feed (while publishing), the metrics board (with --metrics) and the OPC
    UA server (with --opcua)."""

    def __init__(
        self,
        name: str,
        credentials: Credentials,
        board: MetricsBoard | None,
        say: Callable[[str], None],
        changed: Callable[[], None] = lambda: None,
        opcua: OpcUaServer | None = None,
        writes: PlantWrites | None = None,
    ) -> None:
        """``name``: the target in topics and labels; ``say``: tell the user, ``changed``:
        the broker's state changed, for the status line (any thread); ``writes``: where
        an OPC UA client's writes go (when the server takes them)."""
        self._changed = changed
        self.name = name
        self._credentials = credentials
        self._board = board
        self._say = say
        self.mqtt: MqttFeed | None = None
        self._opcua = opcua
        self._writes = writes
        self._paused = False  # the polling, as last told to the OPC UA server
        if opcua is not None:
            opcua.attach(name, writes, say)

    @property
    def broker_state(self) -> str | None:
        """The MQTT feed's :attr:`~...plant.mqtt.MqttFeed.state`; None: not publishing."""
        return self.mqtt.state if self.mqtt is not None else None

    @property
    def publishing(self) -> str | None:
        """Where the values go (``mqtt://broker:1883/line2/cell3/…``), None: nowhere."""
        return str(self.mqtt) if self.mqtt is not None else None

    def publish_to(self, address: MqttAddress, rows: Iterable[RowView]) -> str:
        """Publish from now on to ``address`` (instead of any broker before), starting
        with ``rows`` as they stand. InputError: the extra is missing, the target's name
        cannot be a topic level, or the CA file cannot be used."""
        from ...plant.mqtt import MqttFeed

        topic_level(self.name, "the target's name")
        feed = MqttFeed(address, self._credentials, self.name, self._say, self._changed)
        before = self.stop_publishing()
        self.mqtt = feed
        self._to_mqtt(feed, read(rows), time.time())
        feed.start()
        shown = f"publishing {self.name}'s watched values to {feed} (retained, QoS 1)"
        return shown if before is None else f"{before}; {shown}"

    def stop_publishing(self, wait: bool = False) -> str | None:
        """Stop the MQTT feed (its status topic says ``offline``); what was stopped.

        The feed hands over what is pending and says ``offline`` on a thread of its own,
        so that polling never waits on the broker; ``wait`` (the engine's end) waits."""
        feed, self.mqtt = self.mqtt, None
        if feed is None:
            return None
        if wait:
            feed.stop()
        else:
            threading.Thread(target=feed.stop, name="rac-mqtt-stop", daemon=True).start()
        return f"stopped publishing {self.name}'s values to {feed}"

    def rename(self, name: str) -> str | None:
        """Another target opened (``connect``): its values are published under its own
        name, to the same broker; the old name's figures leave ``/metrics``. What was
        said of it, if publishing."""
        if self._board is not None:
            self._board.forget(self.name)
        if self._opcua is not None:
            self._opcua.detach(self.name, forget=True)
            self._opcua.attach(name, self._writes, self._say)
        old, self.name = self.name, name
        feed = self.mqtt
        if feed is None or name == old:
            return None
        stopped = self.stop_publishing()
        try:
            return f"{stopped}; {self.publish_to(feed.address, ())}"
        except InputError as exc:
            return f"{stopped}; {exc}"

    # ------------------------------------------------------------ the publisher's calls

    def rows(self, changed: Iterable[RowView]) -> None:
        """Rows whose value or health changed since the last flush (a row not read yet
        has nothing to say)."""
        wall = time.time()
        views = read(changed)
        if self.mqtt is not None:
            self._to_mqtt(self.mqtt, views, wall)
        if self._opcua is not None:
            self._opcua.update(self.name, views, wall)
        board = self._board
        if board is not None:
            from ...plant.payload import OK, numeric_fields

            for view in views:
                variant = view.variant
                fields = (
                    numeric_fields(view.var, variant)
                    if view.status == OK and variant is not None
                    else None
                )
                board.set_value(self.name, str(view.var), view.label, fields)

    def removed(self, variables: Iterable[VarRef]) -> None:
        """Rows unwatched: their numbers leave ``/metrics``, and their retained topics
        say so (no value, status ``UNWATCHED``): a dashboard must not read the last value
        as a live one."""
        if self._board is not None:
            for var in variables:
                self._board.remove(self.name, str(var))
        if self._opcua is not None:
            self._opcua.remove(self.name, variables)
        if self.mqtt is not None:
            from ...plant.payload import payload

            wall = time.time()
            for var in variables:
                self.mqtt.retire(str(var), payload(self.name, var, "", None, UNWATCHED, wall))

    def status(self, status: Status) -> None:
        if self._opcua is not None and status.paused != self._paused:
            self._paused = status.paused
            self._opcua.paused(self.name, status.paused)
        if self._board is not None:
            from ...plant.metrics import TargetFigures

            self._board.set_figures(
                self.name,
                TargetFigures(
                    status.connection == "connected",
                    status.rtt,
                    status.cycle_seconds,
                    status.reads,
                    status.interval,
                ),
            )

    def close(self) -> None:
        self.stop_publishing(wait=True)
        if self._opcua is not None:  # the engine ended: its values are no longer read
            self._opcua.detach(self.name)

    def _to_mqtt(self, feed: MqttFeed, views: Iterable[RowView], wall: float) -> None:
        from ...plant.payload import Reading

        name = self.name
        feed.update_many(
            (str(view.var), Reading(name, view.var, view.label, view.variant, view.status, wall))
            for view in views
        )


def read(views: Iterable[RowView]) -> list[RowView]:
    """The rows read at least once: a row not read yet has nothing to say to the plant."""
    return [view for view in views if view.status != WAITING]


def plant_name(host: str | None, port: int, profile: str | None) -> str:
    """A target's name in topics and labels: its profile's, ``sim`` for the built-in
    simulator, else its host (with ``:PORT`` when not RAC's 5006)."""
    if profile is not None:
        return profile
    if host is None:
        return "sim"
    return host if port == 5006 else endpoint(host, port)


def name_of(options: EngineOptions, target: Target) -> str:
    """A target's name in topics and labels: as ``options`` say (a cell's member), or
    after the target."""
    profile = target.profile
    return options.plant_name or plant_name(
        target.host, target.port, profile.name if profile is not None else None
    )


def open_tap(
    options: EngineOptions,
    target: Target,
    say: Callable[[str], None],
    changed: Callable[[], None],
    writes_to: tuple[Submit, Callable[[], Target]] | None = None,
) -> PlantTap:
    """An engine's tap; ``writes_to``: the engine's submit and its rules as they stand,
    for an OPC UA client's writes."""
    from .plant_writes import PlantWrites

    writes = PlantWrites(*writes_to) if writes_to is not None else None
    name = name_of(options, target)
    metrics, opcua = options.metrics, options.opcua
    return PlantTap(name, options.credentials, metrics, say, changed, opcua, writes)


def open_at_start(
    options: EngineOptions,
    target: Target,
    tap: Callable[[], PlantTap],
    say: Callable[[str], None],
) -> None:
    """Publish from the start (--mqtt, else a cell's publish, else the profile's) and
    feed --metrics: said as it begins, or why it cannot. ``tap`` makes the engine's."""
    address = options.publish
    profile = target.profile
    if address is None and profile is not None and profile.publish is not None:
        from ...commands.plant import parse_mqtt_address

        address = parse_mqtt_address(profile.publish)
    if address is None and options.metrics is None and options.opcua is None:
        return
    made = tap()
    if address is not None:
        try:
            say(made.publish_to(address, ()))
        except InputError as exc:
            say(str(exc))
