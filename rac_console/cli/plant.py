"""``--mqtt`` and ``--metrics``: what the engines are to feed the plant, settled once
for the console, the REPL and ``watch``, before anything starts.

A refusal is one line and exit 2 before any controller is asked: a broker address that
cannot be one, a missing extra, a metrics port that cannot be served.
"""

from __future__ import annotations

import argparse
import atexit
import sys
from typing import Any

from ..commands.plant import MqttAddress, parse_metrics_address, parse_mqtt_address
from ..protocol import InputError
from ..protocol.text import terminal_safe

#: The commands that poll, and so have values to feed.
PLANT_COMMANDS = (None, "repl", "watch")


def settle_plant(args: argparse.Namespace) -> bool:
    """``args.plant``: the EngineOptions fields of the plant. False after one line on
    stderr when something asked for cannot be done."""
    notices: list[str] = []
    try:
        args.plant = _plant_options(args, notices)
    except InputError as exc:
        print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
        return False
    args.plant_notices = notices  # the console shows them in its results pane
    if args.command is not None:
        for notice in notices:
            print(f"rac-console: {notice}", file=sys.stderr)
    return True


def _plant_options(args: argparse.Namespace, notices: list[str]) -> dict[str, Any]:
    from ..engine.config import load_config

    config = load_config()
    given = getattr(args, "mqtt", None)
    cell_publish = getattr(args, "cell_publish", None)
    address: MqttAddress | None = None
    if given is not None:
        address = parse_mqtt_address(given)
    elif cell_publish is not None:
        address = parse_mqtt_address(cell_publish)
    targets = [target for _, target in getattr(args, "cell_targets", None) or []] or [args.target]
    publishing = address is not None or any(
        target.profile is not None and target.profile.publish is not None for target in targets
    )
    if publishing:
        from ..plant.extras import need

        need("paho.mqtt.client", "publishing to MQTT")
    options: dict[str, Any] = {"publish": address, "credentials": config.credentials()}
    if getattr(args, "metrics", None) is not None:
        from ..plant.metrics import MetricsBoard, MetricsServer

        where = parse_metrics_address(args.metrics)
        board = MetricsBoard()
        server = MetricsServer(where, board)
        atexit.register(server.stop)
        options["metrics"] = board
        host = f"[{where.host}]" if ":" in where.host else where.host
        notices.append(f"serving the watched values at http://{host}:{server.port}/metrics")
        if not where.loopback:
            notices.append(
                f"--metrics {where} is open to the network: anyone who reaches this "
                "machine can read the watched values"
            )
    return options
