"""Which typed lines may stop to ask before they write, on a ``confirm`` target.

The console holds the keys typed right after such a line (see
:class:`~rac_console.tui.command_line.CommandLine`): typed ahead of a question, a ``y``
and an Enter must neither answer it nor run as a command once it is answered. Pure: the
line is routed by the planner, as the cell will route it.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..commands.routing import OnTarget
from ..engine.commands.builtin import BUILTIN


def written_target(line: str, names: Sequence[str], current: str) -> str | None:
    """The target ``line`` would write to (a ``put``, any raw line but a well-formed
    GET, on the current target or its ``@NAME``), or None: the lines a confirm target's
    rules apply to (the engine may refuse them without asking; never the other way
    round). A line that does not route is refused before anything is asked."""
    route = BUILTIN.plan(line, names, current)
    return route.name if isinstance(route, OnTarget) and route.writes else None


def may_ask(line: str) -> bool:
    """Whether ``line``, on one target, is a write a confirm target asks about."""
    return written_target(line, ("this",), "this") is not None
