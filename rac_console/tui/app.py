"""The Textual console: status line, watch table, frame log, results, command line."""

from __future__ import annotations

import asyncio
import time
from collections import deque
from typing import ClassVar

from rich.text import Text
from textual import on
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.widgets import Footer, RichLog, Static
from textual.worker import Worker, WorkerState

from .. import __version__
from ..commands.outcome import Outcome
from ..core import SIMULATOR_NOTICE, Action, Alert, ConsoleCore, Feedback, LogEvent, Message
from ..core_thread import CoreThread
from ..history import History
from ..protocol.text import terminal_safe
from ..render import error_text, notice_text, outcome_text
from .command_line import CommandLine
from .frame_log import FrameLog
from .status_bar import StatusBar, status_text
from .watch_table import WatchTable

LOG_FLUSH_HZ = 10
#: Candidates listed at most; the list says how many more there are.
MAX_CANDIDATE_LINES = 7
TABLE_REFRESH_HZ = 5


class RacConsoleApp(App[int]):
    CSS_PATH = "app.tcss"
    TITLE = "rac-console"
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("ctrl+q", "quit", "Quit", id="quit", priority=True),
        Binding("f2", "toggle_polling", "Pause polls", id="toggle-polling"),
        Binding("f3", "toggle_poll_frames", "Poll frames", id="toggle-poll-frames"),
        Binding("f4", "toggle_scroll", "Freeze log", id="toggle-scroll"),
        Binding("ctrl+l", "clear_log", "Clear log", id="clear-log"),
    ]

    def __init__(self, core: ConsoleCore, history: History, watch_file: str | None = None) -> None:
        super().__init__()
        self.core = core
        self.core_thread = CoreThread(core)
        self.history = history
        self.watch_file = watch_file
        self._flushes: deque[tuple[float, int]] = deque(maxlen=LOG_FLUSH_HZ * 2)
        self._status = Text()
        self._entered: asyncio.Queue[str] = asyncio.Queue()
        # Kept as attributes: timers and workers never query a DOM being torn down.
        self.status_bar = StatusBar(id="status")
        self.table = WatchTable(id="watch")
        self.frame_log = FrameLog(id="log")
        self.completions = Static(id="completions")
        self.hint = Static(id="hint")
        self.results = RichLog(
            id="results", max_lines=500, wrap=True, markup=False, highlight=False
        )
        self.command_line = CommandLine(
            self.history,
            self._completion_indices,
            id="command",
            placeholder="get P 1 · put IO 20 on · watch IO 0-7 · help",
        )

    def compose(self) -> ComposeResult:
        yield self.status_bar
        yield self.table
        yield self.frame_log
        yield self.completions
        yield self.results
        yield self.hint
        yield self.command_line
        yield Footer()

    async def on_mount(self) -> None:
        self.table.border_title = "Watch"
        self.frame_log.border_title = "Frames (→ sent, ← received)"
        self.core.add_log_listener(self.frame_log.add)
        ui_loop = asyncio.get_running_loop()

        def alert(event: LogEvent) -> None:  # on the session's thread: hand it to ours
            if isinstance(event, Alert):
                ui_loop.call_soon_threadsafe(self.show, Message(event.text, "error"))

        self.core.add_log_listener(alert)
        await self.core_thread.start()
        self.sub_title = self.core.target
        self._welcome()
        if self.watch_file:
            await self.run_line(f"load {self.watch_file}", echo=False)
        self.set_interval(1 / LOG_FLUSH_HZ, self.flush_log)
        self.set_interval(1 / TABLE_REFRESH_HZ, self.refresh_table)
        self.refresh_table()
        self.command_line.focus()
        self.run_worker(self._first_connect(), group="connect", exit_on_error=False)
        self.run_worker(self._run_entered_lines(), group="commands", exit_on_error=False)

    async def on_unmount(self) -> None:
        await self.core_thread.stop()

    def _welcome(self) -> None:
        results = self.results
        if self.core.is_simulator:
            results.write(
                Text.assemble(
                    ("SIMULATOR", "bold black on yellow"),
                    f" {SIMULATOR_NOTICE}.",
                )
            )
        else:
            results.write(
                Text.assemble(
                    ("LIVE", "bold white on red"), f" controller {self.core.host}:{self.core.port}."
                )
            )
        results.write(
            Text(
                f"rac-console {__version__}: type help, or try watch P 0, watch IO 0-7, get S 1",
                style="dim",
            )
        )

    async def _first_connect(self) -> None:
        problem = await self.core_thread.submit(self.core.connect_now())
        if problem is not None:
            self.show(problem)

    def _completion_indices(self) -> set[tuple[str, int]]:
        return self.core.seen | {(v.kind.code, v.index) for v in self.core.watch.rows}

    # -------------------------------------------------------------- refresh

    def flush_log(self) -> None:
        count = self.frame_log.flush()
        self._flushes.append((time.monotonic(), count))

    def frames_per_second(self) -> float:
        if len(self._flushes) < 2:
            return 0.0
        span = self._flushes[-1][0] - self._flushes[0][0]
        total = sum(count for _, count in list(self._flushes)[1:])
        return total / span if span > 0 else 0.0

    def refresh_table(self) -> None:
        _, removed = self.core.watch.take_changes()
        self.table.refresh_rows(self.core.watch.rows, removed, time.monotonic())
        status = status_text(self.core, self.frames_per_second())
        if status != self._status:  # an unchanged line costs no repaint
            self._status = status
            self.status_bar.update(status)

    # ------------------------------------------------------------- commands

    @on(CommandLine.Entered)
    def entered(self, event: CommandLine.Entered) -> None:
        """Queue the line: lines run one at a time, each once, in the order entered."""
        self.completions.remove_class("-visible")
        if not event.line.strip():
            return
        self.command_line.remember(event.line)
        self._entered.put_nowait(event.line)

    async def _run_entered_lines(self) -> None:
        while True:
            line = await self._entered.get()
            try:
                await self.run_line(line)
            except Exception as exc:  # a bug must not end the session at the cell
                self.show(Message(f"internal error: {exc!r}", "error"))

    @on(CommandLine.Completions)
    def list_completions(self, event: CommandLine.Completions) -> None:
        candidates = event.candidates
        shown = (
            candidates
            if len(candidates) <= MAX_CANDIDATE_LINES
            else candidates[: MAX_CANDIDATE_LINES - 1]
        )
        width = max(len(c.text) for c in shown)
        text = Text()
        for n, candidate in enumerate(shown):
            if n:
                text.append("\n")
            text.append(f"{candidate.text:<{width}}", style="bold")
            text.append(f"  {candidate.help}", style="dim")
        if len(shown) < len(candidates):
            more = len(candidates) - len(shown)
            text.append(f"\n… and {more} more: type a letter or two to narrow", style="italic")
        self.completions.update(text)
        self.completions.add_class("-visible")

    @on(CommandLine.Changed)
    def hide_completions(self, event: CommandLine.Changed) -> None:
        self.completions.remove_class("-visible")
        if not event.value:
            self.hint.remove_class("-visible")

    @on(CommandLine.Hint)
    def show_hint(self, event: CommandLine.Hint) -> None:
        """The argument hint, on its own line while a history suggestion holds the grey text."""
        if event.value != self.command_line.value:
            return  # made for a line already changed
        if event.text:
            self.hint.update(Text.assemble(("needs: ", "dim"), (event.text, "italic")))
            self.hint.add_class("-visible")
        else:
            self.hint.remove_class("-visible")

    async def run_line(self, line: str, echo: bool = True) -> None:
        if echo:
            self.results.write(Text(f"› {terminal_safe(line)}", style="bold cyan"))
        for feedback in await self.core_thread.submit(self.core.handle_line(line)):
            self.show(feedback)
        self.refresh_table()

    def show(self, feedback: Feedback) -> None:
        results = self.results
        if isinstance(feedback, Outcome):
            if feedback.ok:
                results.write(outcome_text(feedback))
            else:
                results.write(notice_text(error_text(feedback), error=True))
        elif isinstance(feedback, Message):
            results.write(notice_text(feedback.text, error=feedback.level == "error"))
        elif isinstance(feedback, Action):
            if feedback.name == "clear":
                self.action_clear_log()
            elif feedback.name == "quit":
                self.exit(0)
            elif feedback.name == "frames":
                self.frame_log.show_polls = feedback.on
                self.show(Message("poll frames shown" if feedback.on else "poll frames hidden"))

    @on(Worker.StateChanged)
    def worker_failed(self, event: Worker.StateChanged) -> None:
        """A bug must not end the session at the cell: say so and carry on."""
        if event.state == WorkerState.ERROR and self.is_running:
            self.show(Message(f"internal error: {event.worker.error!r}", "error"))

    # -------------------------------------------------------------- actions

    def action_toggle_polling(self) -> None:
        paused = not self.core.paused
        self.core_thread.call(self.core.set_paused, paused)
        self.show(Message("polling paused (F2 resumes)" if paused else "polling resumed"))
        self.refresh_table()

    def action_toggle_poll_frames(self) -> None:
        log = self.frame_log
        log.show_polls = not log.show_polls
        self.show(
            Message(
                "poll frames shown"
                if log.show_polls
                else "poll frames hidden (typed commands only; F3 shows them)"
            )
        )

    def action_toggle_scroll(self) -> None:
        log = self.frame_log
        log.auto_scroll = not log.auto_scroll
        log.border_title = "Frames" + ("" if log.auto_scroll else " (FROZEN: F4 follows)")
        if log.auto_scroll:
            log.scroll_end(animate=False)

    def action_clear_log(self) -> None:
        self.frame_log.clear()


def run_console(core: ConsoleCore, history: History, watch_file: str | None) -> int:
    return core.exit_status(RacConsoleApp(core, history, watch_file).run() or 0)
