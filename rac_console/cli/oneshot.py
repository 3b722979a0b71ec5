"""The one-shot commands ``get``, ``put``, ``send`` and ``run``, each returning an exit status."""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
from collections.abc import AsyncIterator

from rich.console import Console

from ..commands.language import Get, Put, Raw, parse_command, parse_exchange
from ..commands.outcome import ExitStatus, Outcome, refused, worst
from ..execute import execute
from ..protocol import InputError
from ..render import print_outcome
from .target import open_session


class Output:
    """Where results go: JSON lines, or rich text (plain when not a terminal)."""

    def __init__(self, as_json: bool) -> None:
        self.as_json = as_json
        self.out = Console(highlight=False)
        self.err = Console(stderr=True, highlight=False)

    def show(
        self, outcome: Outcome, extra: dict[str, object] | None = None, prefix: str = ""
    ) -> None:
        if self.as_json:
            data = outcome.to_json() | (extra or {})
            sys.stdout.write(json.dumps(data) + "\n")
            sys.stdout.flush()
            if not outcome.ok:
                self.err.print(
                    "rac-console: " + prefix + outcome.summary(), soft_wrap=True, markup=False
                )
        else:
            print_outcome(self.out, self.err, outcome, prefix)


def _exchange_line(args: argparse.Namespace) -> str:
    if args.command == "send":
        return "send " + args.text
    words = [args.command, args.type, args.index, *getattr(args, "value", [])]
    return " ".join(words)


async def one_command(args: argparse.Namespace) -> ExitStatus:
    """``get``, ``put`` and ``send``: parse, refuse or send, show, exit status."""
    output = Output(args.json)
    line = _exchange_line(args)
    try:
        command = parse_exchange(line)
    except InputError as exc:
        outcome = refused(line, str(exc))
        output.show(outcome)
        return outcome.status
    assert command is not None
    async with open_session(args) as session:
        outcome = await execute(session, command, read_only=args.read_only, line=line)
    output.show(outcome)
    return outcome.status


async def _lines(source: str) -> AsyncIterator[str]:
    if source == "-":
        loop = asyncio.get_running_loop()
        while line := await loop.run_in_executor(None, sys.stdin.readline):
            yield line
        return
    with open(source, encoding="utf-8") as handle:
        for line in handle:
            yield line


async def run_script(args: argparse.Namespace) -> ExitStatus:
    """``run FILE|-``: every line over one session; the worst status is the exit status."""
    output = Output(args.json)
    statuses: list[ExitStatus] = []
    try:
        async with open_session(args) as session:
            number = 0
            async for raw_line in _lines(args.file):
                number += 1
                line = raw_line.rstrip("\r\n")
                try:
                    command = parse_command(line)
                except InputError as exc:
                    outcome = refused(line, str(exc))
                else:
                    if command is None:
                        continue
                    if not isinstance(command, Get | Put | Raw):
                        outcome = refused(
                            line,
                            f"{line.split()[0]!r} works in the console and "
                            "the REPL; run takes get, put, send and GET:/PUT: lines",
                        )
                    else:
                        outcome = await execute(
                            session, command, read_only=args.read_only, line=line
                        )
                output.show(outcome, {"line": number}, prefix=f"line {number}: ")
                statuses.append(outcome.status)
    except OSError as exc:
        output.err.print(f"rac-console: cannot read {args.file}: {exc.strerror}", markup=False)
        return ExitStatus.REFUSED
    return worst(statuses)
