"""A submitted line or command, as the engine queues it.

Its own module: :meth:`Engine.submit` makes one on any thread, and an engine is made
(and may be handed lines) before its parts are, so this loads nothing of them.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ...commands.language import Command
    from ..published.events import Result


@dataclass
class Job:
    """One submitted line or command; a cancel belongs to it and to no other.

    Its :class:`Result` goes to the outbox (``publish``), and then to ``then`` on the
    engine's thread: a cell learns there that its line ended (and starts the next, with
    no front end draining), or takes the feedback of one step of a line it answers as a
    whole (unpublished: the front ends see the cell's one answer)."""

    seq: int
    what: str | Command
    shown: str | None = None  # how a command object is shown (a typed line shows itself)
    then: Callable[[Result], None] | None = None
    publish: bool = True
    source: str | None = None  # its frames say who asked (``OPC UA``): not a typed line
    #: While it holds, the job may run (asked before it starts and before each send): a
    #: plant's write, only on the target and within the time its client waits for it.
    valid: Callable[[], bool] | None = None
    _cancelled: threading.Event = field(default_factory=threading.Event, repr=False)

    @property
    def line(self) -> str | None:
        return self.what if isinstance(self.what, str) else self.shown

    def cancel(self) -> None:
        self._cancelled.set()

    def cancelled(self) -> bool:
        return self._cancelled.is_set() or (self.valid is not None and not self.valid())
