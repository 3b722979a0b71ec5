"""The lines the console hands its cell, typed or made by a key on a row, until their
answers: which one runs, how long it has, which keys typed meanwhile are held.

Lines run one at a time, each once, in order (the cell's queue); Esc cancels the
running one and those behind it. A write that may stop to ask holds the keys typed after
its Enter, so that nothing typed ahead answers its question (see :class:`CommandLine`):
which lines those are is read from the route the cell planned the line to when it
started it at once (:meth:`Cell.enter`), never from a second plan here. :attr:`Lines.pending`
is this thread's own record of the lines not answered yet (the running line's clock, Esc,
the footer): a front end never reads the cell's queue, which other threads move.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from ..present.status import writes_refused
from .command_line import CommandLine

if TYPE_CHECKING:
    from ..commands.language import Command
    from ..commands.routing import Route
    from ..engine.cell.cell import Cell
    from .members import Members


class Lines:
    """Lines handed to the cell and not answered yet, and the one holding the keys."""

    def __init__(
        self,
        cell: Cell,
        members: Members,
        command_line: CommandLine,
        changed: Callable[[], None],
    ) -> None:
        self.cell = cell
        self.members = members
        self.command_line = command_line
        self.changed = changed  # a line started: the footer's keys and the clock follow
        #: seq -> (line, when typed), in the order submitted.
        self.pending: dict[int, tuple[str, float]] = {}
        #: The line whose question keys typed ahead must not answer.
        self.held_seq: int | None = None
        #: Keys its question dropped, said after its answer (not before its echo).
        self._dropped = 0

    def submit(self, line: str, command: Command | None = None, target: str | None = None) -> int:
        """Every line the console hands the cell (typed, or made by a key on a row:
        then ``command`` is run as it is on ``target`` (None: the current one), never
        parsed, and ``line`` shows it): counted as running or queued until its result,
        and cancelled by Esc. Its number."""
        return self._hand_over(line, command, target)[0]

    def _hand_over(
        self, line: str, command: Command | None = None, target: str | None = None
    ) -> tuple[int, bool]:
        """:meth:`submit`; and whether the line may stop to ask before it writes: a
        write on a ``confirm`` target, started at once with nothing of the console's
        before it (a write queued behind a long wait must not hold the keys typed
        meanwhile)."""
        queued = bool(self.pending)
        entered = self.cell.enter(line, command, target)
        self.pending[entered.seq] = (line, time.monotonic())
        self.changed()
        return entered.seq, not queued and self._asks(entered.route)

    def enter(self, line: str, may_hold: bool) -> bool:
        """A line typed (or pasted) and entered, handed to the cell at once; True when
        the keys typed after it are held until it asked or ended (``may_hold``: the
        command line holds them)."""
        if not line.strip():
            return False
        self.command_line.remember(line)
        seq, asks = self._hand_over(line)
        if not (may_hold and asks) or self.held_seq is not None:
            return False
        self.held_seq = seq
        return True

    def answered(self, seq: int) -> int:
        """Line ``seq`` has its result: the keys it held go on. Returns how many keys its
        question dropped, to be said after its answer."""
        dropped = 0
        if seq == self.held_seq:
            self.held_seq = None
            dropped, self._dropped = self._dropped, 0
            self.command_line.post_message(CommandLine.Release())
        self.pending.pop(seq, None)
        return dropped

    def dropped(self, count: int) -> bool:
        """``count`` keys typed ahead of a question were dropped: kept to be said after
        the held line's answer (True), or to be said now when it has ended (False)."""
        if self.held_seq is None:
            return False
        self._dropped += count
        return True

    def toggle(self, line: str, command: Command, target: str | None) -> int:
        """Space on a row: ``command`` handed to the cell as ``line``; when it may ask,
        the keys typed after the Space are held as after a typed write's Enter."""
        seq, asks = self._hand_over(line, command, target)
        if asks and self.held_seq is None:
            self.command_line.hold()
            self.held_seq = seq
        return seq

    def _asks(self, route: Route | None) -> bool:
        """Whether a line planned to ``route`` may stop to ask before it writes: a write
        to a ``confirm`` target whose rules let it write (None: not started yet)."""
        from ..present.type_ahead import written_target

        name = written_target(route) if route is not None else None
        status = self.members.state_of(name).status if name is not None else None
        return status is not None and status.writes == "confirm" and not writes_refused(status)

    def running(self) -> tuple[str, float, int] | None:
        """The oldest line not answered yet (the one running: lines run in order), how
        long ago it was typed, and how many wait behind it."""
        if not self.pending:
            return None
        line, since = next(iter(self.pending.values()))
        return line, time.monotonic() - since, len(self.pending) - 1

    def cancel(self) -> bool:
        """Esc: the running line ends, and those typed behind it are not run. False when
        nothing was running."""
        if not self.pending:
            return False
        self.cell.cancel(queued=True)
        return True
