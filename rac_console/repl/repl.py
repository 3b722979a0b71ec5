"""The line REPL: one prompt, the shared command language, results printed with rich."""

from __future__ import annotations

import asyncio
import contextlib
import signal
from collections.abc import Callable
from typing import Any

from prompt_toolkit import PromptSession
from prompt_toolkit.application import get_app_or_none, run_in_terminal
from prompt_toolkit.formatted_text import FormattedText
from prompt_toolkit.input import Input
from prompt_toolkit.keys import Keys
from prompt_toolkit.output import Output
from rich.console import Console, RenderableType
from rich.live import Live
from rich.table import Table
from rich.text import Text

from ..commands.language import Unwatch, VarRef, Watch
from ..commands.outcome import ExitStatus, Outcome
from ..engine import (
    Alert,
    Batch,
    ConfirmWrite,
    EngineLike,
    Message,
    Note,
    Result,
    RowView,
    Status,
    UiStep,
)
from ..engine.cell.cell import Cell
from ..present.banner import repl_banner
from ..present.batches import BatchReader
from ..present.cell_view import by_target, cell_targets
from ..present.completion import WHOLE_LIST, hint
from ..present.frames import frame_line
from ..present.heap import keep_full_collections_rare
from ..present.history import History, is_refused
from ..present.render import error_text, make_console, notice_text, outcome_text
from ..present.status import connect_targets
from ..present.table_cells import watch_table
from ..session import Frame
from .asking import ask_write
from .prompt_parts import (
    STYLE,
    HintProcessor,
    LineCap,
    RacCompleter,
    RacLexer,
    SharedHistory,
    SharedSuggest,
    cell_toolbar_fragments,
    prompt_fragments,
    toolbar_fragments,
)
from .terminal import keys_held, no_mouse

STOP_KEYS = {Keys.Enter, Keys.ControlM, Keys.ControlJ, Keys.ControlC, Keys.ControlD, "q"}
LIVE_REFRESH_SECONDS = 0.25
#: Drains at most this often while nothing is awaited (frames and rows of polls).
DRAIN_SECONDS = 0.1


class Repl(BatchReader):
    """Runs typed lines on the engine and prints what the outbox brings back."""

    def __init__(
        self,
        cell: Cell | EngineLike,
        history: History,
        console: Console,
        *,
        input: Input | None = None,
        output: Output | None = None,
    ) -> None:
        self.cell = cell if isinstance(cell, Cell) else Cell.of(cell)
        self.history = history
        self.console = console
        self.frames = False
        self.lost = False
        self.statuses: dict[str, Status] = {}  # each target's, by name
        self.rows_of: dict[str, dict[VarRef, RowView]] = {m.name: {} for m in self.cell.members}
        self._ran_on: dict[int, str] = {}  # the target each awaited Result came from
        self._waiting: dict[int, asyncio.Future[Result]] = {}
        self._wake = asyncio.Event()
        self._closing = False
        self._submitted = asyncio.Event()  # a line was submitted: drain without a pause
        self.asking: ConfirmWrite | None = None  # the confirm question on screen
        self._confirm_prompt: PromptSession[str] | None = None
        self._questions: set[asyncio.Task[None]] = set()
        self._printing: set[asyncio.Future[None]] = set()  # lines waiting to go above a prompt
        self.prompt: PromptSession[str] = PromptSession(
            message=self.prompt_message,
            history=SharedHistory(history),
            auto_suggest=SharedSuggest(history),
            completer=RacCompleter(
                self._seen,
                connect_targets(self.cell.members[0].engine.profiles),
                cell_targets(self.cell),
            ),
            complete_while_typing=False,
            # The menu's room: a short list (the 9 types) whole, as the console lists it;
            # a longer one scrolls.
            reserve_space_for_menu=WHOLE_LIST + 1,
            lexer=RacLexer(),
            input_processors=[HintProcessor()],
            bottom_toolbar=self.toolbar,
            key_bindings=no_mouse(),
            style=STYLE,
            input=input,
            output=output,
        )
        LineCap(lambda text: self._print(notice_text(text, error=True))).attach(
            self.prompt.default_buffer
        )

    # ------------------------------------------------------------- prompt

    @property
    def status(self) -> Status | None:
        """The current target's status (the prompt's and the toolbar's)."""
        return self.statuses.get(self.cell.current)

    @property
    def rows(self) -> dict[VarRef, RowView]:
        """The current target's watched rows."""
        return self.rows_of[self.cell.current]

    def _seen(self) -> frozenset[tuple[str, int]]:
        """Indices used or watched (the engine counts watched ones as used)."""
        return self.status.seen if self.status is not None else frozenset()

    def prompt_message(self) -> FormattedText:
        current = None if self.cell.single else self.cell.current
        return prompt_fragments(self.status, self.lost, current)

    def toolbar(self) -> FormattedText:
        status = self.status
        rtt = status.rtt if status is not None else None
        rtt_text = f"rtt {rtt * 1000:.2f} ms" if rtt is not None else "rtt –"
        if self.cell.single:
            parts: list[Any] = list(
                toolbar_fragments(status) if status is not None else [("", " starting ")]
            )
        else:
            parts = list(cell_toolbar_fragments(self.cell.names, self.statuses, self.cell.current))
        parts.append(("", f" {rtt_text} "))
        if self.frames:
            parts.append(("", " frames on "))
        buffer = self.prompt.default_buffer
        needs = hint(buffer.text) if buffer.suggestion is not None else ""
        if needs:  # the history suggestion holds the grey text: the hint shows here
            parts.append(("class:toolbar.hint", f" needs: {needs} "))
        return FormattedText(parts)

    # ------------------------------------------------------------- output

    def _print(self, *objects: RenderableType, soft_wrap: bool | None = None) -> None:
        """Print on lines of their own. While a prompt is on screen (the drain runs
        beside it: an alert, a frame, the first connection's failure) prompt-toolkit
        takes the prompt away, the lines are printed, and the prompt is drawn again
        below them; written straight out they landed inside the prompt's line."""
        self._run_printing(lambda: self.console.print(*objects, soft_wrap=soft_wrap))

    def _run_printing(self, write: Callable[[], None]) -> None:
        app = get_app_or_none()
        if app is None or not app.is_running:
            write()
            return
        task = asyncio.ensure_future(run_in_terminal(write))
        self._printing.add(task)
        task.add_done_callback(self._printing.discard)

    # ------------------------------------------------------------- outbox

    def drain(self) -> None:
        """Take everything the targets published: state first, then events in order."""
        for name, batch in self.cell.drain():
            self.read(name, batch)

    def take_status(self, target: str, status: Status) -> None:
        self.statuses[target] = status

    def take_rows(self, target: str, batch: Batch) -> None:
        batch.apply_rows(self.rows_of[target])

    def take_result(self, target: str | None, result: Result) -> None:
        waiter = self._waiting.pop(result.seq, None)
        if waiter is not None and target is not None:  # read once the line's answer is in
            self._ran_on[result.seq] = target
        if waiter is not None and not waiter.done():
            waiter.set_result(result)
        else:
            self._show_result(result, target)

    def take_confirm(self, target: str | None, question: ConfirmWrite) -> None:
        by = None if self.cell.single else target
        task = asyncio.get_running_loop().create_task(self.confirm(question, by))
        self._questions.add(task)
        task.add_done_callback(self._questions.discard)

    # Named by their target when several are open: an alert (a recording stopped)
    # always; with ``frames on``, every typed frame, dimmed, and the log's marks.

    def take_alert(self, target: str | None, alert: Alert) -> None:
        self._print(self._by(target, notice_text(alert.text, error=alert.local_failure)))

    def take_note(self, target: str | None, note: Note) -> None:
        if self.frames:  # a gap or a failed request, marked
            text = notice_text(f"── {note.text} ──", style="dim")
            self._print(self._by(target, text), soft_wrap=True)

    def take_frame(self, target: str | None, frame: Frame) -> None:
        if self.frames and not frame.poll:
            text = Text(frame_line(frame), style="dim")
            self._print(self._by(target, text), soft_wrap=True)

    def _by(self, target: str | None, text: Text) -> Text:
        return by_target(None if self.cell.single else target, text)

    async def confirm(self, question: ConfirmWrite, target: str | None = None) -> None:
        """A write on a ``confirm`` target asks first (see :func:`ask_write`); in a cell,
        ``target`` (the one the write goes to) leads the target's label."""
        if self._confirm_prompt is None:
            self._confirm_prompt = PromptSession(
                style=STYLE, input=self.prompt.input, output=self.prompt.output
            )
        self.asking = question
        yes = False
        try:
            yes = await ask_write(self._confirm_prompt, question, target, self._print)
        finally:
            self.asking = None
            self.cell.answer_confirm(question.seq, yes)

    async def _drain_forever(self) -> None:
        """Drain when the engine says there is something: nothing wakes an idle REPL.
        While a poll's frames and rows stream in (nothing awaited), drains are at most
        DRAIN_SECONDS apart: one print of many frames, not a wake-up per frame."""
        while not self._closing:
            await self._wake.wait()
            self._wake.clear()
            self.drain()
            if not self._waiting:  # a line submitted meanwhile ends the pause at once
                self._submitted.clear()
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(DRAIN_SECONDS):
                        await self._submitted.wait()

    def _notify(self, loop: asyncio.AbstractEventLoop) -> None:
        """Called on the engine's thread when its outbox stops being empty."""
        loop.call_soon_threadsafe(self._wake.set)

    async def submit(self, line: str | Watch | Unwatch, name: str | None = None) -> Result:
        """Run a line (or a command of the REPL's own, on target ``name``) and wait
        for its result."""
        loop = asyncio.get_running_loop()
        future: asyncio.Future[Result] = loop.create_future()
        cell = self.cell
        # Ctrl-C while a command runs cancels that command, not the REPL (where the loop
        # can take signals: not on Windows, where Ctrl-C keeps its default meaning);
        # taken before the line is submitted, so no Ctrl-C falls between the two.
        with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
            loop.add_signal_handler(signal.SIGINT, cell.cancel)
        seq = cell.submit(line) if isinstance(line, str) else cell.submit_command(line, name=name)
        self._waiting[seq] = future
        self._wake.set()
        self._submitted.set()
        try:
            return await future
        finally:
            with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                loop.remove_signal_handler(signal.SIGINT)

    # -------------------------------------------------------------- loop

    async def run(self) -> int:
        loop = asyncio.get_running_loop()
        self.cell.set_notify(lambda: self._notify(loop))
        self.cell.set_poll_frames(False)  # the REPL never shows a poll's frames
        await asyncio.to_thread(self.cell.start)
        self.drain()
        banner = self.banner()
        if banner is not None:
            self._print(banner, soft_wrap=True)
        drainer = loop.create_task(self._drain_forever())
        try:
            while True:
                try:
                    line = await self.prompt.prompt_async()
                except KeyboardInterrupt:
                    continue  # Ctrl-C clears the line
                except EOFError:
                    break
                with keys_held(self.prompt.input):
                    if not await self.handle(line):
                        break
        finally:
            self._closing = True
            drainer.cancel()
            await asyncio.gather(drainer, *self._printing, return_exceptions=True)
            await asyncio.to_thread(self.cell.stop)
            self.drain()
        return 0

    def banner(self) -> Text | None:
        """The first line: the cell, the simulator, or the live controller with its
        profile and write rules (as the console's welcome says it)."""
        return repl_banner(self.cell.names, self.status)

    def exit_status(self, status: int) -> int:
        for known in self.statuses.values():
            status = known.exit_status(status)
        return status

    async def handle(self, text: str) -> bool:
        """Run what was entered, line by line (a paste may hold several); False when a
        line asks to leave."""
        for line in text.replace("\r\n", "\n").replace("\r", "\n").split("\n"):
            if line.strip() and not await self._handle_line(line):
                return False
        return True

    async def _handle_line(self, line: str) -> bool:
        """Run one line; False when it asks to leave. The history keeps it once its
        result says it was not refused."""
        watched_before = {var for rows in self.rows_of.values() for var in rows}
        self.history.enter(line)
        result = await self.submit(line)
        self.history.settle(line, refused=is_refused(result))
        name = self._ran_on.pop(result.seq, None)
        if isinstance(result.command, Watch) and not _failed(result) and name is not None:
            status = self.statuses.get(name)
            if status is not None and status.csv_log is not None:
                self._show_result(result, name)  # whether the CSV log has these columns
            await self.live_watch(result.command, name, watched_before)
            return True
        return self._show_result(result, name)

    def _show_result(self, result: Result, name: str | None = None) -> bool:
        """Print a result (named by its target when several are open); False when it
        asks to leave."""
        by = None if self.cell.single else name
        for feedback in result.feedback:
            if isinstance(feedback, Outcome):
                self._show_outcome(feedback, by)
            elif isinstance(feedback, Message):
                text = notice_text(feedback.text, error=feedback.level == "error")
                self._print(by_target(by, text))
            elif feedback is UiStep.QUIT:
                return False
            elif feedback is UiStep.CLEAR:
                self._run_printing(self.console.clear)
            elif feedback in (UiStep.FRAMES_ON, UiStep.FRAMES_OFF):
                self.frames = feedback is UiStep.FRAMES_ON
                self._print(f"frames {'on' if self.frames else 'off'}")
        return True

    def _show_outcome(self, outcome: Outcome, by: str | None = None) -> None:
        status = self.statuses.get(by) if by is not None else self.status
        if outcome.status == ExitStatus.TRANSPORT and status is not None and status.has_session:
            self.lost = status.connection != "connected"
            if self.lost:
                text = f"{error_text(outcome)}: the next command reconnects"
                self._print(by_target(by, notice_text(text, error=True)))
                return
        elif outcome.response is not None:
            self.lost = False
        if outcome.ok:
            self._print(by_target(by, outcome_text(outcome)), soft_wrap=True)
        else:
            self._print(by_target(by, notice_text(error_text(outcome), error=True)), soft_wrap=True)

    # ------------------------------------------------------------- watch

    async def live_watch(self, command: Watch, name: str, watched_before: set[VarRef]) -> None:
        """A table (of target ``name``'s rows) updating in place until Enter, q or
        Ctrl-C; then back to the prompt (the rows this watch added go again)."""
        added = [v for v in command.vars if v not in watched_before]
        stop = asyncio.Event()
        keys = self.prompt.input

        def key_pressed() -> None:
            if any(press.key in STOP_KEYS for press in keys.read_keys()):
                stop.set()

        status = self.statuses.get(name)
        period = status.period if status is not None else 0.0
        if self._paused(name):
            self._print(
                notice_text(
                    "polling is paused: these rows wait for resume (Enter, q or Ctrl-C "
                    "returns to the prompt, then type resume)",
                    style="bold yellow",
                )
            )
        else:
            self._print(
                Text(
                    f"watching every {period:g} s: Enter, q or Ctrl-C returns to the prompt",
                    style="dim",
                )
            )
        try:
            with (
                keys.raw_mode(),
                keys.attach(key_pressed),
                Live(
                    self._watch_table(command, name),
                    console=self.console,
                    auto_refresh=False,
                    transient=False,
                ) as live,
            ):
                while not stop.is_set():
                    with contextlib.suppress(TimeoutError):
                        async with asyncio.timeout(LIVE_REFRESH_SECONDS):
                            await stop.wait()
                    self.drain()
                    live.update(self._watch_table(command, name), refresh=True)
        finally:
            if added:
                await self.submit(Unwatch(tuple(added)), name)

    def _paused(self, name: str) -> bool:
        status = self.statuses.get(name)
        return status is not None and status.paused

    def _watch_table(self, command: Watch, name: str) -> Table:
        title = None if self.cell.single else name
        return watch_table(command.vars, self.rows_of[name], self._paused(name), title)


def _failed(result: Result) -> bool:
    return any(isinstance(f, Message) and f.level == "error" for f in result.feedback)


def run_repl(cell: Cell | EngineLike, history: History) -> int:
    """``rac-console repl`` on a terminal."""
    repl = Repl(cell, history, make_console())
    keep_full_collections_rare()  # the start-up's objects frozen: no line waits on a full pass
    return repl.exit_status(asyncio.run(repl.run()))
