"""The job runner: a submitted line or command, parsed once, run by its entry's handler.

The same for every front end: the engine runs each job on its thread; ``rac-console
run`` and the one-shot commands run theirs on the CLI's. Every problem becomes
feedback, never an exception.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...commands.language import Command
from ...commands.routing import Reach
from ...protocol import InputError
from ..published.events import Feedback, Message
from ..setup.where import Where
from .registry import Registry

#: Why a served console does not run a command, by what the command reaches.
SERVED_REFUSALS = {
    Reach.FILES: "it writes or reads files on the machine serving it",
    Reach.NETWORK: "it opens connections from the machine serving it",
}

if TYPE_CHECKING:
    from .context import JobContext


def run_job(
    registry: Registry,
    context: JobContext,
    what: str | Command,
    where: Where,
    line: str | None = None,
) -> tuple[Command | None, list[Feedback]]:
    """Parse ``what`` (a typed line; a command object is run as it is, ``line`` being
    what it was made from), check that its command runs ``where``, and run it: the
    command as parsed and its feedback. ``context``: the engine's for a job an engine
    runs (any command), the CLI's for one on a plain session (the entries whose handler
    takes a :class:`~.context.JobContext`)."""
    command: Command | None = None
    line = what if isinstance(what, str) else line
    try:
        command = registry.parse(what) if isinstance(what, str) else what
        if command is None:
            return None, []
        spec = registry.spec_of(command)
        if not spec.runs_in(where):
            return command, [Message(not_here(registry, spec.name, where), "error")]
        return command, spec.run(context, command, line)
    except InputError as exc:
        return command, [Message(str(exc), "error")]
    except Exception as exc:  # a bug must not end the session at the cell
        return command, [Message(f"internal error: {exc!r}", "error")]


def not_here(registry: Registry, name: str, where: Where) -> str:
    """Why ``name`` does not run ``where``, and what does."""
    spec = registry.get(name)
    if where is Where.SERVED and spec is not None and spec.traits.reaches in SERVED_REFUSALS:
        return f"{name!r} is not for a served console: {SERVED_REFUSALS[spec.traits.reaches]}"
    if where is Where.RUN:
        takes = ", ".join(registry.runs_in(Where.RUN))
        return f"{name!r} works in the console and the REPL; run takes {takes} and GET:/PUT: lines"
    return f"{name!r} does not run in the {where.value}"
