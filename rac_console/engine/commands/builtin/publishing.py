"""``publish``: the watched values to an MQTT broker, from the console or the REPL.

Run on the engine's thread, so the rows it starts with are the ones polled. In a cell a
``publish`` without ``@NAME`` goes to every target (the cell sends it to each and answers
once): the plant wants the cell, not the target the prompt happens to name.
"""

from __future__ import annotations

from collections.abc import Sequence

from ....commands.plant import PUBLISH_USAGE, Publish, parse_publish
from ....commands.routing import Reach, Scope, Traits
from ....protocol.errors import InputError
from ...published.events import Feedback, Message
from ..context import CommandContext
from ..registry import EngineSpec, Option, Sources


def run_publish(context: CommandContext, command: Publish, line: str | None) -> list[Feedback]:
    name = context.plant_name()
    if command.off:
        stopped = context.stop_publishing()
        return [Message(stopped or f"{name} is not publishing: nothing to stop")]
    if command.address is None:
        where = context.publishing_to()
        return [
            Message(
                f"{name}'s watched values go to {where}"
                if where is not None
                else f"{name} is not publishing: {PUBLISH_USAGE}"
            )
        ]
    try:
        said = context.publish_to(command.address)
    except InputError as exc:
        return [Message(str(exc), "error")]
    return [Message(said)]


def _complete(args: list[str], sources: Sources) -> Sequence[Option]:
    if args:
        return ()
    return (
        ("mqtt://", "a broker: mqtt://HOST[:PORT]/PREFIX"),
        ("mqtts://", "a broker over TLS (the CA from the config's [mqtt] or RAC_MQTT_CA_FILE)"),
        ("off", "stop publishing"),
    )


PUBLISH_SPEC = EngineSpec(
    "publish",
    "mqtt://HOST[:PORT]/PREFIX | off",
    "publish the watched values to an MQTT broker (retained, one topic each)",
    parse_publish,
    run_publish,
    "publish mqtt://broker.plant/line2",
    notes=(
        "topics: PREFIX/<target>/<variable> (PREFIX/cell3/IO128), a JSON object each: "
        "value, vartype, status, time; PREFIX/<target>/status says online or offline",
        "user, password and CA file: the config's [mqtt] table or RAC_MQTT_USERNAME, "
        "RAC_MQTT_PASSWORD, RAC_MQTT_CA_FILE, never the address",
        "nothing is read from the broker: no message can write to a controller",
    ),
    complete=_complete,
    types=(Publish,),
    traits=Traits(scope=Scope.EVERY_TARGET, reaches=Reach.NETWORK),
)

#: This module's commands.
SPECS = (PUBLISH_SPEC,)
