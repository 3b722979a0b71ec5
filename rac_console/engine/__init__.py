"""The engine: all mutable state of a console session, on a thread of its own.

Thread rules (the only ones; nothing else is shared):

- The engine's thread owns everything that changes: the target (and the built-in
  simulator's thread), the one :class:`~rac_console.session.Session`, the watch list,
  the poller, the recorder, the figures. Only that thread reads or writes them.
- Any thread may call :meth:`Engine.submit` (lines go through a thread-safe queue and
  run one at a time, in order, between polls) and :meth:`Engine.stop`.
- The engine publishes immutable events (:mod:`.events`: frames with their parsed
  reply, notes, alerts, results, row views, the status) to one :class:`Outbox`. A front
  end drains it on its own thread and schedule, and never reads an engine attribute.
  Row views and the status replace the ones not yet drained.
- Nothing here imports Textual, prompt-toolkit or rich; the process-wide interpreter
  settings (switch interval, signal handlers) are left alone.

:class:`Engine` and its module load on first use (PEP 562): the one-shot commands use
the events and the handlers without the engine's thread, so they skip its imports.
"""

from typing import TYPE_CHECKING, Any

from .events import (
    CONFIRM_GUARD_SECONDS,
    Alert,
    ConfirmWrite,
    Cycle,
    Feedback,
    Measured,
    Message,
    Note,
    Result,
    RowView,
    Status,
    UiStep,
)
from .outbox import Batch, Outbox

if TYPE_CHECKING:
    from .engine import DEFAULT_INTERVAL, SIMULATOR_NOTICE, Engine, EngineOptions

#: Names served from :mod:`.engine` when first asked for.
_FROM_ENGINE_MODULE = frozenset({"DEFAULT_INTERVAL", "SIMULATOR_NOTICE", "Engine", "EngineOptions"})


def __getattr__(name: str) -> Any:
    """The engine's names, imported when first used rather than with the package."""
    if name in _FROM_ENGINE_MODULE:
        from . import engine

        value = getattr(engine, name)
        globals()[name] = value  # asked once: later uses find it as a plain attribute
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "CONFIRM_GUARD_SECONDS",
    "DEFAULT_INTERVAL",
    "SIMULATOR_NOTICE",
    "Alert",
    "Batch",
    "ConfirmWrite",
    "Cycle",
    "Engine",
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
