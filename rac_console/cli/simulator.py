"""``rac-console sim``: serve the simulator until interrupted."""

from __future__ import annotations

import argparse
import sys
from dataclasses import fields

from ..sim.faults import FaultSettings
from ..sim.server import SimulatorServer, is_loopback


async def serve(args: argparse.Namespace) -> int:
    if not is_loopback(args.bind):
        print(
            f"rac-console: warning: the simulator listens on {args.bind}, beyond loopback: "
            "anyone who can reach this machine can read and write its variables",
            file=sys.stderr,
        )
    try:
        faults = FaultSettings(**{f.name: getattr(args, f.name) for f in fields(FaultSettings)})
        faults.check()
    except ValueError as exc:
        print(f"rac-console: {exc}", file=sys.stderr)
        return 2
    try:
        server = await SimulatorServer(args.bind, args.sim_port, faults=faults).start()
    except (OSError, UnicodeError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or "not an address this machine has"
        print(
            f"rac-console: cannot listen on {args.bind}:{args.sim_port}: {reason}", file=sys.stderr
        )
        return 3
    print(f"RC8 simulator listening on {server.host}:{server.port} (Ctrl-C to stop)", flush=True)
    if faults.active or faults.max_sessions:
        print(f"faults: {faults.describe()}", flush=True)
    try:
        await server.serve_forever()
    finally:
        await server.stop()
    return 0
