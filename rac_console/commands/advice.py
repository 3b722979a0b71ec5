"""What a refusal tells its reader to do, in the words of the front end they use.

A refusal says why in words every front end shares, and then how to do it instead; only
that last part differs: the command line adds ``--yes``, a script passes ``yes=True``.
Each front end's words are declared here once, and whatever refuses (the write gate, the
planner, the resolver of targets) is handed the :class:`Advice` of the front end it
serves: no front end rewrites another's message.
"""

from __future__ import annotations

from dataclasses import dataclass

from .cells import DEMO_CELL


@dataclass(frozen=True)
class Advice:
    """How to do what was refused, as one front end says it."""

    #: How to answer a ``confirm`` target's question ahead.
    say_yes: str
    #: How to open the demo cell's simulators.
    demo_cell: str
    #: How to open other targets than a cell's.
    other_targets: str
    #: An address written as it is taken, and an IPv6 address.
    address: str
    ipv6: str
    #: How to write a typed put of ``{code}`` ``{index}`` (a format string).
    typed_put: str

    def put(self, code: str, index: int) -> str:
        """The typed put of one variable, as this front end writes it."""
        return self.typed_put.format(code=code, index=index)


#: The command line's, the console's, the REPL's and a served console's.
COMMAND_LINE = Advice(
    say_yes="add --yes to write from a script or the command line",
    demo_cell=f"try --cell {DEMO_CELL}",
    other_targets="start rac-console with -H a,b or --cell NAME",
    address="connect HOST or connect HOST:PORT",
    ipv6="connect [::1] or [::1]:5006",
    typed_put="put {code} {index} VALUE",
)

#: A Python script's (``import rac_console as rac``).
LIBRARY = Advice(
    say_yes="pass yes=True or confirm=a function to rac.connect (or rac.cell) to write",
    demo_cell=f'try rac.cell("{DEMO_CELL}")',
    other_targets="open them with rac.connect(...) or rac.cell([...])",
    address='"HOST" or "HOST:PORT"',
    ipv6='"[::1]" or "[::1]:5006"',
    typed_put='put("{code}", {index}, VALUE)',
)
