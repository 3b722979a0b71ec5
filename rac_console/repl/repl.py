"""The line REPL: one prompt, the shared command language, results printed with rich."""

from __future__ import annotations

import asyncio
import contextlib
import time

from prompt_toolkit import PromptSession
from prompt_toolkit.auto_suggest import AutoSuggestFromHistory
from prompt_toolkit.formatted_text import FormattedText
from prompt_toolkit.input import Input
from prompt_toolkit.keys import Keys
from prompt_toolkit.output import Output
from rich.console import Console
from rich.live import Live
from rich.table import Table
from rich.text import Text

from ..client import Frame
from ..commands.completion import hint
from ..commands.language import Watch, parse_command
from ..commands.outcome import ExitStatus, Outcome
from ..core import SIMULATOR_NOTICE, Action, Alert, ConsoleCore, LogEvent, Message
from ..frames import frame_line
from ..history import History
from ..protocol import InputError
from ..protocol.text import terminal_safe
from ..render import error_text, make_console, notice_text, outcome_text
from ..watch import age_text
from ..watch_cells import status_cell, value_cell
from .prompt_parts import STYLE, HintProcessor, RacCompleter, RacLexer, SharedHistory

STOP_KEYS = {Keys.Enter, Keys.ControlM, Keys.ControlJ, Keys.ControlC, Keys.ControlD, "q"}
LIVE_REFRESH_SECONDS = 0.25


class Repl:
    def __init__(
        self,
        core: ConsoleCore,
        history: History,
        console: Console,
        *,
        input: Input | None = None,
        output: Output | None = None,
    ) -> None:
        self.core = core
        self.console = console
        self.frames = False
        self.lost = False
        self.prompt: PromptSession[str] = PromptSession(
            message=self._prompt_message,
            history=SharedHistory(history),
            auto_suggest=AutoSuggestFromHistory(),
            completer=RacCompleter(self._seen),
            complete_while_typing=False,
            lexer=RacLexer(),
            input_processors=[HintProcessor()],
            bottom_toolbar=self._toolbar,
            style=STYLE,
            input=input,
            output=output,
        )

    # ------------------------------------------------------------- prompt

    def _seen(self) -> set[tuple[str, int]]:
        return self.core.seen | {(v.kind.code, v.index) for v in self.core.watch.rows}

    def _prompt_message(self) -> FormattedText:
        session = self.core.session
        if session is None or (self.lost and session.state != "connected"):
            return FormattedText([("class:prompt.off", "not connected"), ("", "> ")])
        if self.core.is_simulator:
            return FormattedText([("class:prompt.sim", "sim"), ("", "> ")])
        return FormattedText(
            [("class:prompt.live", f"{self.core.host}:{self.core.port}"), ("", "> ")]
        )

    def _toolbar(self) -> FormattedText:
        session = self.core.session
        rtt = session.last_rtt if session is not None else None
        parts = [
            (
                "",
                f" {self.core.target}  rtt {rtt * 1000:.2f} ms "
                if rtt is not None
                else f" {self.core.target}  rtt – ",
            )
        ]
        if self.frames:
            parts.append(("", " frames on "))
        buffer = self.prompt.default_buffer
        needs = hint(buffer.text) if buffer.suggestion is not None else ""
        if needs:  # the history suggestion holds the grey text: the hint shows here
            parts.append(("class:toolbar.hint", f" needs: {needs} "))
        if self.core.read_only:
            parts.append(("class:toolbar.readonly", " READ-ONLY "))
        return FormattedText(parts)

    # -------------------------------------------------------------- loop

    async def run(self) -> int:
        await self.core.start()
        self.core.add_log_listener(self._echo)
        if self.core.is_simulator:
            self.console.print(
                Text.assemble(
                    ("sim", "bold yellow"),
                    f": {SIMULATOR_NOTICE}. help lists the commands; Ctrl-D leaves.",
                )
            )
        try:
            while True:
                try:
                    line = await self.prompt.prompt_async()
                except KeyboardInterrupt:
                    continue  # Ctrl-C clears the line
                except EOFError:
                    break
                if not await self.handle(line):
                    break
        finally:
            await self.core.stop()
        return 0

    async def handle(self, text: str) -> bool:
        """Run what was entered, line by line (a paste may hold several); False when a
        line asks to leave."""
        for line in text.replace("\r\n", "\n").replace("\r", "\n").split("\n"):
            if line.strip() and not await self._handle_line(line):
                return False
        return True

    async def _handle_line(self, line: str) -> bool:
        """Run one line; False when it asks to leave."""
        try:
            command = parse_command(line)
        except InputError as exc:
            self.console.print(notice_text(str(exc), error=True))
            return True
        if isinstance(command, Watch):
            await self.live_watch(line, command)
            return True
        for feedback in await self.core.handle_line(line):
            if isinstance(feedback, Outcome):
                self._show_outcome(feedback)
            elif isinstance(feedback, Message):
                self.console.print(notice_text(feedback.text, error=feedback.level == "error"))
            elif isinstance(feedback, Action):
                if feedback.name == "quit":
                    return False
                if feedback.name == "clear":
                    self.console.clear()
                elif feedback.name == "frames":
                    self.frames = feedback.on
                    self.console.print(f"frames {'on' if feedback.on else 'off'}")
        return True

    def _show_outcome(self, outcome: Outcome) -> None:
        session = self.core.session
        if outcome.status == ExitStatus.TRANSPORT and session is not None:
            self.lost = session.state != "connected"
            if self.lost:
                self.console.print(
                    notice_text(f"{error_text(outcome)}: the next command reconnects", error=True)
                )
                return
        elif outcome.response is not None:
            self.lost = False
        if outcome.ok:
            self.console.print(outcome_text(outcome), soft_wrap=True)
        else:
            self.console.print(notice_text(error_text(outcome), error=True), soft_wrap=True)

    def _echo(self, event: LogEvent) -> None:
        """``frames on``: every frame, dimmed, as it crosses the wire (not during a watch);
        an alert (a recording stopped) always."""
        if isinstance(event, Alert):
            self.console.print(notice_text(event.text, error=True))
        elif self.frames and isinstance(event, str):  # a gap or a failed request, marked
            self.console.print(notice_text(f"── {event} ──", style="dim"), soft_wrap=True)
        elif self.frames and isinstance(event, Frame) and not event.poll:
            self.console.print(Text(frame_line(event), style="dim"), soft_wrap=True)

    # ------------------------------------------------------------- watch

    async def live_watch(self, line: str, command: Watch) -> None:
        """A table updating in place until Enter, q or Ctrl-C; then back to the prompt."""
        added = [v for v in command.vars if v not in self.core.watch.rows]
        for feedback in await self.core.handle_line(line):
            if isinstance(feedback, Message) and feedback.level == "error":
                self.console.print(notice_text(feedback.text, error=True))
                return
        stop = asyncio.Event()
        keys = self.prompt.input

        def key_pressed() -> None:
            if any(press.key in STOP_KEYS for press in keys.read_keys()):
                stop.set()

        self.console.print(
            Text(
                f"watching every {self.core.period:g} s: Enter, q or Ctrl-C returns to the prompt",
                style="dim",
            )
        )
        try:
            with (
                keys.raw_mode(),
                keys.attach(key_pressed),
                Live(
                    self._watch_table(command),
                    console=self.console,
                    auto_refresh=False,
                    transient=False,
                ) as live,
            ):
                while not stop.is_set():
                    with contextlib.suppress(TimeoutError):
                        await asyncio.wait_for(stop.wait(), LIVE_REFRESH_SECONDS)
                    live.update(self._watch_table(command), refresh=True)
        finally:
            self.core.watch.remove(tuple(added))

    def _watch_table(self, command: Watch) -> Table:
        table = Table(box=None, pad_edge=False, header_style="bold")
        for title in ("Variable", "Label", "Status", "Changed", "Value"):
            table.add_column(title)
        now = time.monotonic()
        for var in command.vars:
            row = self.core.watch.rows.get(var)
            if row is not None:
                table.add_row(
                    str(var),
                    Text(terminal_safe(row.label)),
                    status_cell(row),
                    age_text(row, now),
                    value_cell(row, now),
                )
        return table


def run_repl(core: ConsoleCore, history: History) -> int:
    """``rac-console repl`` on a terminal."""
    return core.exit_status(asyncio.run(Repl(core, history, make_console()).run()))
