"""``rac-console check`` on a terminal: one line per step, ok in green, FAILED in red.

The words are :mod:`rac_console.commands.check`'s; this adds only colour, and passes
everything through :func:`terminal_safe` (a host name or a reply may hold anything).
"""

from __future__ import annotations

from rich.text import Text

from ..commands.check import CheckReport, heading, step_line
from ..protocol.text import terminal_safe

_STYLES = {True: "green", False: "bold red", None: "dim"}


def check_lines(
    report: CheckReport, profile: str | None, simulator: bool, no_profile: str | None = None
) -> list[Text]:
    """The heading, then each step's line in the colour of how it went."""
    lines = [Text(terminal_safe(heading(report, profile, simulator)), style="bold")]
    for step in report.steps:
        line = Text(terminal_safe(step_line(step, report, no_profile)))
        line.stylize(_STYLES[step.ok], 16, 23)  # the status column
        lines.append(line)
    return lines
