"""The lines the console hands its cell, typed or made by a key on a row, until their
answers: which one runs, how long it has, which keys typed meanwhile are held.

Lines run one at a time, each once, in order (the cell's queue); Esc cancels the
running one and those behind it. A write that may stop to ask holds the keys typed after
its Enter, so that nothing typed ahead answers its question (see :class:`CommandLine`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from ..present.status import writes_refused
from .command_line import CommandLine

if TYPE_CHECKING:
    from ..commands.language import Command
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
        and cancelled by Esc."""
        cell = self.cell
        seq = cell.submit(line) if command is None else cell.submit_command(command, line, target)
        self.pending[seq] = (line, time.monotonic())
        self.changed()
        return seq

    def entered(self, line: str, held: bool) -> None:
        """A line typed and entered (``held``: the keys after it wait for its question)."""
        if not line.strip():
            if held:
                self.command_line.post_message(CommandLine.Release())
            return
        self.command_line.remember(line)
        queued = bool(self.pending)
        seq = self.submit(line)
        if held:
            self.hold_keys(seq, queued)

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

    def may_ask(self, line: str) -> bool:
        """Whether this line, run now, may stop to ask before it writes: a write on a
        ``confirm`` target with nothing running before it (a write queued behind a
        long wait must not hold the keys typed meanwhile)."""
        from ..present.type_ahead import written_target

        if self.pending:
            return False
        name = written_target(line, self.cell.names, self.cell.current)
        status = self.members.state_of(name).status if name is not None else None
        return status is not None and status.writes == "confirm" and not writes_refused(status)

    def hold_keys(self, seq: int, queued: bool) -> None:
        """The keys typed after line ``seq`` are held until it asked or ended; a line that
        turned out to be queued behind another holds none."""
        if queued or self.held_seq is not None:
            self.command_line.post_message(CommandLine.Release())
        else:
            self.held_seq = seq

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
