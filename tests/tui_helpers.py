"""Helpers for Pilot tests: build the app on a private history, wait on conditions."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path

from textual.pilot import Pilot
from textual.widgets import RichLog

from rac_console.engine import Engine
from rac_console.present.history import History
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.frame_log import FrameLog

#: The request timeout of the tests' consoles unless a test gives its own: one no busy
#: machine reaches (a reply an in-process simulator sends late is no timeout of the
#: controller's); a test of timeouts says how short it wants them.
REQUEST_TIMEOUT = 30.0


def make_app(
    tmp_path: Path,
    host: str | None = None,
    port: int = 5006,
    *,
    read_only: bool = False,
    interval: float = 0.05,
    timeout: float = REQUEST_TIMEOUT,
    watch_file: str | None = None,
    record: str | None = None,
) -> RacConsoleApp:
    """The console on a private history; it records the wire to ``wire.jsonl`` in
    ``tmp_path`` (read by :class:`FrameTap`) unless given another ``record`` file."""
    engine = Engine(
        host,
        port,
        timeout=timeout,
        read_only=read_only,
        interval=interval,
        record=record or str(tmp_path / WIRE_RECORD),
        cycles=True,  # as the console's engine: trends are drawn from its cycles
    )
    return RacConsoleApp(engine, History(tmp_path / "history"), watch_file)


WIRE_RECORD = "wire.jsonl"


#: How long :func:`until` lets the app run for what it waits on: only the point where a
#: wait is called hung (a busy machine can take seconds), never a figure a test checks.
DEADLINE = 20.0


async def until(
    pilot: Pilot, predicate: Callable[[], bool], what: str, timeout: float = DEADLINE
) -> None:
    """Let the app run until ``predicate`` holds; fail naming ``what`` after ``timeout``."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await pilot.pause(0.05)


async def type_line(pilot: Pilot, line: str, enter: bool = True, keys: bool = False) -> None:
    """Enter a line as if pasted (``keys=True`` types it key by key), then press Enter."""
    if keys:
        await pilot.press(*line)
    else:
        from rac_console.tui.command_line import CommandLine

        command_line = pilot.app.query_one(CommandLine)
        command_line.insert_text_at_cursor(line)
    if enter:
        await pilot.press("enter")


def log_text(app: RacConsoleApp) -> str:
    return "\n".join(app.query_one(FrameLog).lines)


def results_text(app: RacConsoleApp) -> str:
    return "\n".join(strip.text for strip in app.query_one("#results", RichLog).lines)


class FrameTap:
    """What really went on the wire: the ``--record`` file the app under test writes."""

    def __init__(self, tmp_path: Path) -> None:
        self.path = tmp_path / WIRE_RECORD

    def _records(self) -> list[dict[str, object]]:
        if not self.path.exists():
            return []
        return [json.loads(line) for line in self.path.read_text().splitlines() if line]

    @property
    def sent(self) -> list[bytes]:
        """Requests as sent (ASCII, CR included): the recorder escapes nothing in them."""
        return [str(r["text"]).encode("ascii") + b"\r" for r in self._records() if r["dir"] == "tx"]
