"""Which typed lines may stop to ask before they write, on a ``confirm`` target.

The console holds the keys typed right after such a line (see
:class:`~rac_console.tui.command_line.CommandLine`): typed ahead of a question, a ``y``
and an Enter must neither answer it nor run as a command once it is answered. Pure: the
rule reads the route the cell planned the line to (:meth:`Cell.enter`), so a line is
planned once, by the registry that runs it.
"""

from __future__ import annotations

from ..commands.routing import OnTarget, Route


def written_target(route: Route) -> str | None:
    """The target a line planned to ``route`` writes to (a ``put``, any raw line but a
    well-formed GET, on the current target or its ``@NAME``), or None: the lines a
    confirm target's rules apply to (the engine may refuse them without asking; never
    the other way round). A line that does not route is refused before anything is
    asked."""
    return route.name if isinstance(route, OnTarget) and route.writes else None


def may_ask(line: str) -> bool:
    """Whether ``line``, on one target with the built-in commands, is a write a confirm
    target asks about: the rule above for a line planned on its own (the console reads
    the route its cell planned a line to instead, and plans nothing here)."""
    from ..engine.commands.builtin import BUILTIN

    return written_target(BUILTIN.plan(line, ("this",), "this")) is not None
