"""``rac-console sim``: serve the simulator until interrupted."""

from __future__ import annotations

import argparse
import sys

from ..sim.server import SimulatorServer, is_loopback


async def serve(args: argparse.Namespace) -> int:
    if not is_loopback(args.bind):
        print(
            f"rac-console: warning: the simulator listens on {args.bind}, beyond loopback: "
            "anyone who can reach this machine can read and write its variables",
            file=sys.stderr,
        )
    try:
        server = await SimulatorServer(args.bind, args.sim_port).start()
    except OSError as exc:
        print(
            f"rac-console: cannot listen on {args.bind}:{args.sim_port}: {exc.strerror}",
            file=sys.stderr,
        )
        return 3
    print(f"RC8 simulator listening on {server.host}:{server.port} (Ctrl-C to stop)", flush=True)
    try:
        await server.serve_forever()
    finally:
        await server.stop()
    return 0
