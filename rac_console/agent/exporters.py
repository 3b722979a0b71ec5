"""The agent's own feeds of the plant (``agent --mqtt``, ``--metrics``, ``--log-csv``):
an engine of the agent's per target, watching what the agent was told to export (a
``--watch`` list, a cell's ``watch`` lines), on the target's one connection like any
client's. What it says (a broker that went away, a list that cannot be loaded) goes to
the agent's log; it runs whoever is attached, from the agent's start to its stop.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from ..commands.language import Watch
from ..engine import Alert, Engine, EngineOptions, Message, Outbox, Result
from ..engine.setup.where import Where
from ..engine.watch.watchlist import load
from ..session import Session

#: The client name an exporter's requests carry in the other clients' frame logs.
EXPORTER = "exporter"
#: How often the exporters' outboxes are read at most when nothing wakes them.
WAKE_EVERY = 0.5


@dataclass(frozen=True)
class Export:
    """What one held target exports: the watch list file and the cell's watch lines."""

    name: str
    watch_file: str | None
    lines: tuple[str, ...]
    plant_name: str | None = None  # the target's name in topics and labels (a cell's)


class Exporters:
    """The exporters' engines, and the thread that tells the agent's log what they say."""

    def __init__(self, say: Callable[[str], None]) -> None:
        self.say = say
        self.engines: list[tuple[str, Engine]] = []
        self._wake = threading.Event()
        self._stopping = False
        self._rows: dict[str, set[object]] = {}  # the rows each exporter watches
        self._reader = threading.Thread(target=self._read, name="rac-agent-exporters", daemon=True)

    def start(
        self,
        exports: Sequence[Export],
        options: EngineOptions,
        sessions: Callable[[str], Callable[[str, int, float], Session]],
        targets: Callable[[str], object],
    ) -> None:
        """An engine per export, started on the agent's connection to its target
        (``sessions(name)`` makes its sessions; ``targets(name)`` the target's rules)."""
        for export in exports:
            engine = Engine(
                target=targets(export.name),  # type: ignore[arg-type]
                options=replace(
                    options, sessions=sessions(export.name), plant_name=export.plant_name
                ),
                outbox=Outbox(notify=self._wake.set),
                where=Where.COMMAND_LINE,
            )
            engine.start(connect=True)
            if export.watch_file is not None:  # checked as the agent started
                for var, label, every in load(export.watch_file):
                    engine.submit_command(Watch((var,), label, every))
            for line in export.lines:
                engine.submit(f"watch {line}")
            self.engines.append((export.name, engine))
        if self.engines:
            self._reader.start()

    def _read(self) -> None:
        while not self._stopping:
            self._wake.wait(WAKE_EVERY)
            self._wake.clear()
            for name, engine in self.engines:
                batch = engine.outbox.drain()
                rows = self._rows.setdefault(name, set())
                rows.update(batch.rows)
                rows.difference_update(batch.removed)
                for event in batch.events:
                    self._tell(name, event)

    def _tell(self, name: str, event: object) -> None:
        if isinstance(event, Alert):
            self.say(f"{EXPORTER} on {name}: {event.text}")
        elif isinstance(event, Result):
            for said in event.feedback:
                if isinstance(said, Message) and said.level == "error":
                    self.say(f"{EXPORTER} on {name}: {said.text}")

    def status(self) -> list[dict[str, object]]:
        """Each exporter's target and how many rows it watches."""
        return [{"target": name, "rows": len(self._rows.get(name, ()))} for name, _ in self.engines]

    def stop(self) -> None:
        self._stopping = True
        self._wake.set()
        for _, engine in self.engines:
            engine.stop()
        if self._reader.is_alive():
            self._reader.join(5)
