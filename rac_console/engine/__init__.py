"""The engine: all mutable state of a console session, on a thread of its own.

Thread rules (the only ones; nothing else is shared):

- The engine's thread owns everything that changes: the target (and the built-in
  simulator's thread), the one :class:`~rac_console.session.Session`, the watch list,
  the poller, the recorder, the figures. Only that thread reads or writes them.
- Any thread may call :meth:`Engine.submit` (lines go through a thread-safe queue and
  run one at a time, in order, between polls) and :meth:`Engine.stop`.
- The engine publishes immutable events (:mod:`.published.events`: frames with their
  parsed reply, notes, alerts, results, row views, the status) to one :class:`Outbox`. A
  front end drains it on its own thread and schedule, and never reads an engine
  attribute. Row views and the status replace the ones not yet drained.
- Nothing here imports Textual, prompt-toolkit or rich; the process-wide interpreter
  settings (switch interval, signal handlers) are left alone.

Every name loads with its module on first use (PEP 562, :mod:`rac_console.lazy`): the
one-shot commands use the events and the handlers without the engine's thread, so they
skip its imports, and the console settles its target (``engine.setup.config``) before its
first paint without loading the events.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from .published.events import (
        CONFIRM_GUARD_SECONDS,
        Alert,
        ConfirmWrite,
        Cycle,
        Feedback,
        Measured,
        Note,
        Result,
        RowView,
    )
    from .published.feedback import Message, UiStep
    from .published.outbox import Batch, Outbox
    from .published.status import Status
    from .setup.options import DEFAULT_INTERVAL, EngineOptions
    from .thread.engine import SIMULATOR_NOTICE, Engine
    from .thread.surface import EngineLike

#: Where each name lives: imported when first used, so ``engine.setup.config`` (read to
#: settle a target) or the outbox load neither the events nor the engine's parts.
_WHERE = {
    **dict.fromkeys(("SIMULATOR_NOTICE", "Engine"), ".thread.engine"),
    "EngineLike": ".thread.surface",
    **dict.fromkeys(("DEFAULT_INTERVAL", "EngineOptions"), ".setup.options"),
    **dict.fromkeys(
        (
            "CONFIRM_GUARD_SECONDS",
            "Alert",
            "ConfirmWrite",
            "Cycle",
            "Feedback",
            "Measured",
            "Note",
            "Result",
            "RowView",
        ),
        ".published.events",
    ),
    **dict.fromkeys(("Message", "UiStep"), ".published.feedback"),
    "Status": ".published.status",
    **dict.fromkeys(("Batch", "Outbox"), ".published.outbox"),
}
__getattr__ = exports(__name__, _WHERE)


__all__ = [
    "CONFIRM_GUARD_SECONDS",
    "DEFAULT_INTERVAL",
    "SIMULATOR_NOTICE",
    "Alert",
    "Batch",
    "ConfirmWrite",
    "Cycle",
    "Engine",
    "EngineLike",
    "EngineOptions",
    "Feedback",
    "Measured",
    "Message",
    "Note",
    "Outbox",
    "Result",
    "RowView",
    "Status",
    "UiStep",
]
