"""``--mqtt`` and ``--metrics``: what the engines are to feed the plant, settled once
for the console, the REPL and ``watch``, before anything starts.

A refusal is one line and exit 2 before any controller is asked: a broker address that
cannot be one, a missing extra, a metrics port that cannot be served.
"""

from __future__ import annotations

import argparse
import atexit
import sys
from pathlib import Path
from typing import Any

from ..commands.config_keys import withheld_notice
from ..commands.plant import (
    MetricsAddress,
    MqttAddress,
    parse_metrics_address,
    parse_mqtt_address,
)
from ..protocol import InputError
from ..protocol.text import terminal_safe


def settle_plant(args: argparse.Namespace) -> bool:
    """``args.plant``: the EngineOptions fields of the plant. False after one line on
    stderr when something asked for cannot be done."""
    notices: list[str] = []
    try:
        args.plant = _plant_options(args, notices)
    except InputError as exc:
        print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
        return False
    args.plant_notices = notices  # said by say_plant_notices once the command is checked
    return True


def say_plant_notices(args: argparse.Namespace) -> None:
    """The plant's notices (``serving … /metrics``) on stderr: said by the REPL and
    ``watch`` once their own arguments have been accepted, never before a refusal (the
    console shows them in its results pane)."""
    for notice in getattr(args, "plant_notices", ()):
        print(f"rac-console: {notice}", file=sys.stderr)


def _plant_options(args: argparse.Namespace, notices: list[str]) -> dict[str, Any]:
    from ..engine.setup.config import load_config

    config = load_config()
    if (withheld := withheld_notice(config.withheld)) is not None:  # a served console's
        notices.append(withheld)
    given = getattr(args, "mqtt", None)
    cell_publish = getattr(args, "cell_publish", None)
    address: MqttAddress | None = None
    if given is not None:
        address = parse_mqtt_address(given)
    elif cell_publish is not None:
        address = parse_mqtt_address(cell_publish)
    members = getattr(args, "cell_targets", None) or [("", args.target)]
    publishing = address is not None or any(
        target.profile is not None and target.profile.publish is not None for _, target in members
    )
    credentials = config.credentials()
    if publishing:
        from ..plant.extras import need

        need("paho.mqtt.client", "publishing to MQTT")
        _check_ca_file(credentials.ca_file)
        from ..commands.plant import topic_level
        from ..engine.polling.plant_tap import name_of
        from ..engine.setup.options import EngineOptions

        for name, target in members:
            named = EngineOptions(plant_name=None if len(members) == 1 else name)
            topic_level(name_of(named, target), "the target's name")
        tls = address.tls if address is not None else False
        if credentials.password and not tls:
            notices.append(
                "the MQTT password goes to the broker unencrypted (mqtt://): use mqtts:// "
                "where the network is not the cell's own"
            )
    options: dict[str, Any] = {"publish": address, "credentials": credentials}
    if getattr(args, "metrics", None) is not None:
        from ..plant.metrics import MetricsBoard
        from ..plant.metrics_server import MetricsServer

        where = parse_metrics_address(args.metrics)
        board = MetricsBoard()
        server = MetricsServer(where, board)
        atexit.register(server.stop)
        options["metrics"] = board
        served = MetricsAddress(where.host, server.port)  # port 0: the one it took
        notices.append(f"serving the watched values at http://{served}/metrics")
        if not where.loopback:
            notices.append(
                f"--metrics {where} is open to the network: anyone who reaches this "
                "machine can read the watched values"
            )
    _opcua_options(args, options, notices)
    return options


def _opcua_options(args: argparse.Namespace, options: dict[str, Any], notices: list[str]) -> None:
    """``--opcua``: the server started now (a port taken, a missing extra: refused)."""
    import os

    from ..commands.opcua import PASSWORD_ENV, opcua_settings

    given = getattr(args, "opcua", None)
    extra = [
        name for name in ("opcua_security", "opcua_user") if getattr(args, name, None) is not None
    ]
    if getattr(args, "opcua_writes", False):
        extra.append("opcua_writes")
    if given is None:
        if extra:
            shown = ", ".join("--" + name.replace("_", "-") for name in extra)
            raise InputError(f"{shown} go with --opcua opc.tcp://HOST:PORT")
        return
    settings = opcua_settings(
        given,
        getattr(args, "opcua_security", None),
        bool(getattr(args, "opcua_writes", False)),
        getattr(args, "opcua_user", None),
        os.environ.get(PASSWORD_ENV),
    )
    from ..plant.extras import need

    need("asyncua", "--opcua")
    from ..plant.opcua_server import OpcUaServer

    server = OpcUaServer(settings)
    server.start()
    atexit.register(server.stop)
    options["opcua"] = server
    writes = "writes through the write gate" if settings.writes else "read-only"
    notices.append(f"serving the watched values over OPC UA at {server} ({writes})")
    if server.certificate is not None:
        from ..plant.opcua_security import opcua_folder

        made = "made now" if server.certificate_made else "its certificate"
        notices.append(
            f"OPC UA certificate ({made}): {server.certificate}; clients are let in when "
            f"their certificate is in {opcua_folder() / 'trusted'}"
        )


def _check_ca_file(ca_file: str | None) -> None:
    """The CA file, if one is named, must be a certificate TLS can use: refused now,
    not found out when the first connection fails."""
    if ca_file is None:
        return
    import ssl

    where = "RAC_MQTT_CA_FILE, or ca_file in the config's [mqtt]"
    path = Path(ca_file).expanduser()
    if not path.is_file():
        raise InputError(
            f"the MQTT CA file {ca_file} ({where}) is not a file: name the CA certificate "
            "(PEM) that signs the broker's"
        )
    try:
        ssl.create_default_context(cafile=str(path))
    except (ssl.SSLError, OSError, ValueError) as exc:
        why = getattr(exc, "reason", None) or getattr(exc, "strerror", None) or exc
        raise InputError(
            f"the MQTT CA file {ca_file} ({where}) holds no certificate TLS can use: {why}"
        ) from None
