"""What the console does with what its engines publish: the frames to the log, the
results to the results pane, the rows and trends to the members, a question to ask.

The console's :class:`~rac_console.present.batches.BatchReader`: the switch over event
kinds is the one all front ends share; here is only what the console does with each.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING

from ..engine.published.feedback import Message, UiStep
from ..present.batches import BatchReader, removed_rows
from ..present.history import is_refused
from ..present.status import placeholder_for
from ..protocol.text import counted, terminal_safe
from . import row_keys
from .command_line import dropped_text

if TYPE_CHECKING:
    from ..engine.published.events import Alert, ConfirmWrite, Cycle, Feedback, Note, Result
    from ..engine.published.outbox import Batch
    from ..engine.published.status import Status
    from ..present.history import History
    from ..session import Frame
    from .file_writes import FileWrites
    from .lines import Lines
    from .members import Members
    from .panes import Panes


class ConsoleFeed(BatchReader):
    """The engines' batches, taken into the console's members and panes. What only the
    screen can do is handed in: ``ask`` a write's question, ``close_question`` when its
    line ended first, ``mark_target`` (the border), ``subtitle`` (the app's), ``refresh`` the table
    and ``quit``."""

    def __init__(
        self,
        members: Members,
        panes: Panes,
        lines: Lines,
        history: History,
        files: FileWrites,
        *,
        ask: Callable[[ConfirmWrite, str | None], None],
        close_question: Callable[[int], None],
        mark_target: Callable[[Status], None],
        subtitle: Callable[[str], None],
        refresh: Callable[[], None],
        quit: Callable[[], None],
    ) -> None:
        self.members = members
        self.cell_mode = members.cell_mode
        self.panes = panes
        self.lines = lines
        self.history = history
        self.files = files  # history lines, written off the screen's loop
        self.ask = ask
        self.close_question = close_question
        self.mark_target = mark_target
        self.subtitle = subtitle
        self.refresh_table = refresh
        self.quit = quit

    def _named(self, target: str | None) -> str | None:
        """How a target is named on screen: in a cell only."""
        return target if self.cell_mode else None

    def take_status(self, target: str, status: Status) -> None:
        state = self.members.states[target]
        old = state.status
        if old is not None and status.target_id != old.target_id:
            state.trends.clear()  # the last target's samples are not the new one's
        state.status = status
        log = self.panes.frame_log
        statuses = [s.status for s in self.members.states.values() if s.status]
        log.slow_after = max(s.timeout for s in statuses) / 2  # a slow reply stands out
        if self.cell_mode:
            if old is None:
                self.subtitle(terminal_safe(f"cell: {', '.join(self.members.cell.names)}"))
            return
        if old is None or status.target != old.target:
            self.subtitle(terminal_safe(status.target))
        if old is None or shown_target(status) != shown_target(old):
            self.mark_target(status)
        self.panes.command_line.placeholder = placeholder_for(status)

    def take_rows(self, target: str, batch: Batch) -> None:
        state = self.members.states[target]
        batch.apply_rows(state.rows)
        state.removed |= batch.removed
        row_keys.forget_rows(self.panes, state, removed_rows(batch))
        state.removed -= batch.rows.keys()

    def take_result(self, target: str | None, result: Result) -> None:
        if result.line is not None:  # a typed line: kept by the history unless refused
            self.files.run(partial(self.history.settle, result.line, refused=is_refused(result)))
        self.close_question(result.seq)
        dropped = self.lines.answered(result.seq)
        if self.members.state_of(target).toggles.result(result):
            self.refresh_table()
        from ..present.render import echo_text

        if result.line is not None:  # the line echoed, in a cell after its target
            self.panes.results.write(echo_text(result.line, self._named(target)))
        for feedback in result.feedback:
            self.show(feedback)
        if dropped:  # the keys its question dropped, said after its answer
            self.show(Message(dropped_text(dropped)))

    def take_cycle(self, target: str | None, cycle: Cycle) -> None:
        """A poll cycle: its values go to its target's trends (not an earlier target's,
        drained after the change)."""
        state = self.members.state_of(target)
        if state.status is not None and cycle.target_id != state.status.target_id:
            return
        state.trends.add_cycle(cycle)
        if state.toggles.cycle(cycle):
            self.refresh_table()

    def take_confirm(self, target: str | None, question: ConfirmWrite) -> None:
        self.ask(question, target)

    def take_alert(self, target: str | None, alert: Alert) -> None:
        named = self._named(target)
        self.panes.frame_log.add(alert, named)
        text = alert.text if named is None else f"{named}: {alert.text}"
        self.show(Message(text, "error" if alert.local_failure else "info"))

    def take_note(self, target: str | None, note: Note) -> None:
        self.panes.frame_log.add(note, self._named(target))

    def take_frame(self, target: str | None, frame: Frame) -> None:
        self.panes.frame_log.add(frame, self._named(target))

    def take_shed(self, target: str | None, frames: int, cycles: int) -> None:
        from ..engine.published.events import Alert

        lost = [counted(n, w) for n, w in ((frames, "frame"), (cycles, "poll cycle")) if n]
        self.panes.frame_log.add(Alert(f"{' and '.join(lost)} not shown: the screen fell behind"))

    def show(self, feedback: Feedback) -> None:
        """A message, an outcome or a UI step, in the results."""
        from ..commands.outcome import Outcome
        from ..present.render import error_text, notice_text, outcome_text

        results = self.panes.results
        if isinstance(feedback, Outcome):
            shown = outcome_text(feedback) if feedback.ok else None
            results.write(shown or notice_text(error_text(feedback), error=True))
        elif isinstance(feedback, Message):
            results.write(notice_text(feedback.text, error=feedback.level == "error"))
        elif feedback is UiStep.CLEAR:
            self.panes.frame_log.clear()
        elif feedback is UiStep.QUIT:
            self.quit()
        elif feedback in (UiStep.FRAMES_ON, UiStep.FRAMES_OFF):
            shown_polls = feedback is UiStep.FRAMES_ON
            self.panes.frame_log.show_polls = shown_polls
            self.show(Message("poll frames shown" if shown_polls else "poll frames hidden"))


def shown_target(status: Status) -> tuple[str | None, str | None, str | None]:
    """What the border shows of a target: its profile, label and colour."""
    return status.profile, status.label, status.colour
