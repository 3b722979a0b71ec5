"""``rac-console agent``: hold the targets for every front end of this user; ``agent
status``: what a running agent holds. And the one place a front end asks to go through
a running agent (:func:`attach_for`)."""

from __future__ import annotations

import argparse
import json
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from ..protocol import InputError
from ..protocol.text import terminal_safe

if TYPE_CHECKING:
    from ..agent.exporters import Export
    from ..commands.language import Command
    from ..commands.target import Target
    from ..engine import EngineLike, EngineOptions, Feedback, Outbox
    from ..engine.cell.cell import Attach
    from ..engine.setup.where import Where


def attach_for(args: argparse.Namespace, kind: str, where: Where) -> Attach | None:
    """How ``kind`` (the console, the REPL, ``watch``, …) attaches a target to a running agent;
    None with ``--direct``. A front end that feeds the plant itself (``--mqtt``,
    ``--metrics``, ``--opcua``) goes direct: the agent's exporters are the agent's own."""
    if getattr(args, "direct", False):
        return None

    def attach(
        target: Target, options: EngineOptions, outbox: Outbox, numbers: Iterator[int]
    ) -> EngineLike | None:
        from ..agent.endpoint import present

        feeds = options.publish or options.metrics or options.opcua
        if feeds is not None or not present():
            return None
        from ..agent.client import Refused, attach
        from ..engine.setup.where import Where

        try:
            engine = attach(
                target, options, client=kind, where=where, outbox=outbox, numbers=numbers
            )
        except Refused as exc:
            print(f"rac-console: {terminal_safe(str(exc))}; going direct", file=sys.stderr)
            return None
        if engine is not None and where is Where.COMMAND_LINE:  # the others show it
            say_via(engine.name)
        return engine

    return attach


def say_via(client: str) -> None:
    """A command line's word that it went through the agent: on stderr, so that its
    stdout is the same as without one."""
    print(f"rac-console: via agent, as {terminal_safe(client)}", file=sys.stderr)


#: The longest a one-shot command waits for the agent's answer beyond its own timeout
#: (the agent answers every line; this only bounds a wait on an agent that hangs).
ANSWER_MARGIN = 30.0


def one_line_via_agent(
    args: argparse.Namespace, command: Command, line: str
) -> list[Feedback] | None:
    """``get``, ``put`` or ``send`` through a running agent that holds the target: what
    it said, as the command line shows it run here; None to run it here (no agent, not
    held, ``--direct``, or a ``--record``/``--log`` file of the command's own). Said on
    stderr only: stdout and ``--json`` are as without an agent."""
    lines = AgentLines.attach(args, args.target, "command")
    if lines is None:
        return None
    try:
        return lines.run(command, line)
    finally:
        lines.close()


class AgentLines:
    """A command line's lines through the agent, one at a time, each answered before
    :meth:`run` returns (``get``, ``put``, ``send``; each target of ``run``)."""

    def __init__(self, engine: EngineLike, args: argparse.Namespace) -> None:
        self.engine, self.yes, self.timeout = engine, bool(args.yes), float(args.timeout)
        self._woken = threading.Event()
        engine.outbox.notify = self._woken.set
        engine.start()

    @classmethod
    def attach(
        cls, args: argparse.Namespace, target: Target, kind: str, where: Where | None = None
    ) -> AgentLines | None:
        """Attached to the agent that holds ``target``, said on stderr; None to go
        direct (no agent, not held, ``--direct``, or a ``--record``/``--log`` file of
        the command's own)."""
        if getattr(args, "direct", False) or args.record or getattr(args, "transcript", None):
            return None
        from ..agent.endpoint import present

        if not present():
            return None
        from ..agent.client import Refused, attach
        from ..engine import EngineOptions
        from ..engine.setup.where import Where

        options = EngineOptions(timeout=args.timeout, verify=args.verify, frames=False)
        try:
            engine = attach(target, options, client=kind, where=where or Where.COMMAND_LINE)
        except Refused as exc:
            print(f"rac-console: {terminal_safe(str(exc))}; going direct", file=sys.stderr)
            return None
        if engine is None:
            return None
        say_via(engine.name)
        return cls(engine, args)

    def run(self, command: Command, line: str, longest: float = 0.0) -> list[Feedback]:
        """What the line came to; an answer that does not come in time (``longest``
        for a line that may take long, such as ``latency``, plus the usual wait) is an
        outcome unknown (a write may have gone out)."""
        from ..engine import ConfirmWrite, Result

        engine, woken = self.engine, self._woken
        answer: list[Result] = []
        seq = engine.submit_command(command, line, then=answer.append)
        deadline = time.monotonic() + longest + self.timeout * 4 + ANSWER_MARGIN
        while not answer and time.monotonic() < deadline:
            woken.wait(0.1)
            woken.clear()
            for event in engine.outbox.drain().events:
                if isinstance(event, ConfirmWrite) and event.seq == seq:
                    engine.answer_confirm(seq, self.yes)  # --yes: said yes ahead
        if answer:
            return list(answer[0].feedback)
        from ..agent.lines import may_write
        from ..commands.outcome import ExitStatus, Outcome

        writes = may_write(engine.registry, command)
        return [Outcome(None, ExitStatus.TRANSPORT, error=UNANSWERED_IN_TIME, input_line=line,
                        write_unknown=writes)]  # fmt: skip

    def close(self) -> None:
        self.engine.stop()


#: Said when the agent took a line and gave no answer in time.
UNANSWERED_IN_TIME = (
    "the agent gave no answer in time: the outcome is unknown (use --direct, or "
    "rac-console agent status)"
)


def holder_said(host: str, port: int) -> str | None:
    """What ``check`` says when a running agent holds ``host:port``, else None."""
    from ..agent.endpoint import present

    if not present():
        return None
    from ..agent.client import agent_status

    status = agent_status()
    if status is None or status.get("op") != "status":
        return None
    for target in status.get("targets", ()):
        if target.get("address") == f"{host}:{port}":
            return (
                f"the agent (pid {status.get('pid')}) holds this controller: the console, "
                "the REPL and the commands (get, put, send, watch, run, latency) go "
                "through its one connection (--direct: their own; rac-console agent "
                "status says who is attached)"
            )
    return None


def agent_command(args: argparse.Namespace) -> int:
    if args.action == "status":
        return _status(args)
    return _run(args)


def _say(text: str) -> None:
    print(f"{time.strftime('%H:%M:%S')} agent: {terminal_safe(text)}", flush=True)


def _run(args: argparse.Namespace) -> int:
    from ..agent.server import Agent
    from ..engine.cell.cell import member_name

    members: list[tuple[str, Target]] = getattr(args, "cell_targets", None) or [
        (member_name(args.target), args.target)
    ]
    try:
        exports = _exports(args, ["sim" if t.host is None else name for name, t in members])
    except InputError as exc:
        print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
        return 2
    held: list[tuple[str, Target]] = []
    stops = {}
    for name, target in members:
        if target.host is None:  # the built-in simulator, listening for the clients
            from dataclasses import replace

            from ..sim.thread import SimulatorThread

            simulator = SimulatorThread().start()
            target = replace(target, host=simulator.host, port=simulator.port, simulated=True)
            name, stops[name] = "sim", simulator.stop
        held.append((name, target))
    agent = Agent(held, timeout=args.timeout, say=_say, simulators=stops)
    try:
        endpoint = agent.open()
    except OSError as exc:  # EndpointError, or a folder that cannot be made
        print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
        for stop in stops.values():
            stop()
        return 2
    if args.record or getattr(args, "transcript", None):
        from ..engine.files.frame_files import FrameFiles

        try:
            files = FrameFiles(args.record, getattr(args, "transcript", None), _say)
        except InputError as exc:
            print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
            agent.stop()
            return 2
        agent.keep_frames(files)
        _say("every frame to the controller goes to " + " and ".join(
            str(path) for path in (args.record, getattr(args, "transcript", None)) if path
        ))  # fmt: skip
    for notice in getattr(args, "plant_notices", ()):
        _say(notice)
    if exports:
        try:
            agent.export(exports, _export_options(args))
        except InputError as exc:  # a --log-csv file that cannot be written
            print(f"rac-console: {terminal_safe(str(exc))}", file=sys.stderr)
            agent.stop()
            return 2
        rows = ", ".join(e.name for e in exports)
        _say(f"feeding the plant the watch list's rows of {rows}, whoever is attached")
    _say(f"listening on {endpoint} for this user's front ends; Ctrl-C stops")
    serving = threading.Thread(target=agent.serve, name="rac-agent-accept", daemon=True)
    serving.start()
    _stop_on_terminate()
    try:
        while serving.is_alive():
            serving.join(0.5)
    except KeyboardInterrupt:
        pass
    agent.stop()
    _say("stopped")
    return 0


def _exports(args: argparse.Namespace, names: list[str]) -> list[Export]:
    """What the agent's own feeds watch: the ``--watch`` list (on the first target, as
    the console loads it) and a cell's watch lines, each on its target. InputError when
    a feed has nothing to feed, or a list is given for no feed."""
    from ..agent.exporters import Export
    from ..engine.watch.watchlist import load

    plant = getattr(args, "plant", {})
    feeds = any(plant.get(name) is not None for name in ("publish", "metrics", "opcua"))
    feeds = feeds or getattr(args, "log_csv", None) is not None
    feeds = feeds or any(getattr(t.profile, "publish", None) for t in _targets(args))
    watch_file = getattr(args, "watch", None)
    lines: dict[str, list[str]] = {}
    for line in getattr(args, "cell_watch", ()):
        name, _, rest = line.partition(" ")
        lines.setdefault(name, []).append(rest)
    if not feeds:
        if watch_file is not None:
            raise InputError(
                "agent --watch FILE gives the agent's own feeds their rows: give --mqtt, "
                "--metrics, --opcua or --log-csv with it (the clients watch what they like)"
            )
        return []
    if watch_file is None and not lines:
        raise InputError(
            "the agent's --mqtt, --metrics, --opcua and --log-csv feed the rows of a watch list: "
            "give it with --watch FILE (or a cell's watch lines)"
        )
    if watch_file is not None:
        load(watch_file)  # a broken list is one line now, not a feed that starts half-set
        watch_file = str(Path(watch_file).expanduser().absolute())
    single = len(names) == 1
    return [
        Export(
            name,
            watch_file if n == 0 else None,
            tuple(lines.get(name, ())),
            None if single else name,
        )
        for n, name in enumerate(names)
        if (watch_file is not None and n == 0) or lines.get(name)
    ]


def _targets(args: argparse.Namespace) -> list[Target]:
    return [t for _, t in getattr(args, "cell_targets", None) or [("", args.target)]]


def _export_options(args: argparse.Namespace) -> EngineOptions:
    from ..engine import DEFAULT_INTERVAL, EngineOptions

    return EngineOptions(
        timeout=args.timeout,
        interval=DEFAULT_INTERVAL if args.interval is None else args.interval,
        frames=False,
        log_csv=getattr(args, "log_csv", None),
        **getattr(args, "plant", {}),
    )


def _count(number: int, word: str) -> str:
    return f"{number:,} {word}{'' if number == 1 else 's'}"


def _stop_on_terminate() -> None:
    """SIGTERM (systemd's stop, kill) stops the agent as Ctrl-C does: its clients are
    told, its socket removed."""
    import signal

    def stop(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    if hasattr(signal, "SIGTERM"):
        signal.signal(signal.SIGTERM, stop)


def _status(args: argparse.Namespace) -> int:
    from ..agent.client import agent_status

    status = agent_status()
    if status is None or status.get("op") != "status":
        if args.json:
            print(json.dumps({"running": False}))
        else:
            print("no agent is running for this user", file=sys.stderr)
        return 1
    del status["op"]
    status.pop("proof", None)  # the agent's proof of its token: checked, not shown
    if args.json:
        print(json.dumps({"running": True, **status}))
        return 0
    print(f"agent pid {status['pid']}, listening on {terminal_safe(str(status['endpoint']))}")
    for target in status["targets"]:
        name, address = terminal_safe(target["name"]), terminal_safe(target["address"])
        waiting = target.get("writes_waiting")
        print(
            f"  target {name if name == address else f'{name} {address}'}: "
            f"{terminal_safe(str(target['state']))}, {_count(target['clients'], 'client')}, "
            f"{_count(target['requests'], 'request')}, {target['shared_polls']:,} polls shared"
            + (f", {_count(waiting, 'write')} waiting for an earlier one" if waiting else "")
        )
    for feed in status.get("exporters", ()):
        print(
            f"  exporter on {terminal_safe(feed['target'])}: {_count(feed['rows'], 'row')} "
            "fed to the plant"
        )
    for client in status["clients"]:
        missed = f", {client['missed']} frames missed" if client["missed"] else ""
        print(
            f"  client {terminal_safe(client['name'])} (pid {client['pid']}) on "
            f"{terminal_safe(client['target'])}{missed}"
        )
    return 0
