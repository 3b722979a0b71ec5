"""The console's panes, made once: what the console screen lays out and its key
handlers act on (:mod:`.row_keys`, :mod:`.console`).

Kept as one object so that timers and workers never query a DOM being torn down, and
so that the functions acting on several panes name what they touch.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from textual import events
from textual.containers import Horizontal, Vertical
from textual.widget import AwaitMount, Widget
from textual.widgets import Static

from ..engine.setup.where import Where
from ..present.status import placeholder_for
from ..protocol.text import terminal_safe
from .command_line import CommandLine
from .completion_list import CompletionList
from .filter_line import FilterLine
from .frame_log import FrameLog
from .io_panel import IoPanel, WatchArea
from .results import ResultsLog
from .row_detail import RowDetail
from .status_bar import StatusBar
from .trend_view import TrendView
from .watch_table import TableFilter, WatchTable

if TYPE_CHECKING:
    from textual.screen import Screen

    from ..engine.published.events import RowView
    from ..present.history import History
    from ..present.trends import TrendStore
    from .members import Members


FILTER_HINT = "filter frames: text, or a variable (IO128, I 10, P[3]): its requests and replies"
CELL_FILTER_HINT = "filter frames: @NAME for a target, text, or a variable (@robotB IO64)"

#: Panes shorter than this (a terminal under 15 lines) show no frame log: its two lines
#: would take the table's rows; the table and the results share the room.
SHORT_ROWS = 12


class PaneArea(Vertical):
    """The panes between the status line and the command line: they share what the
    terminal leaves them, so the command line below is always on screen; the completion
    list floats over their bottom (a layer of its own), pushing nothing."""

    def on_resize(self, event: events.Resize) -> None:
        self.set_class(event.size.height < SHORT_ROWS, "-short")


@dataclass
class Panes:
    """Every widget of the console; the hidden ones join the screen after its first
    paint (see :meth:`mount_hidden`)."""

    status_bar: StatusBar
    table: WatchTable
    table_filter: TableFilter
    trend_view: TrendView
    row_detail: RowDetail
    frame_log: FrameLog
    log_filter: FilterLine
    io_panel: IoPanel
    watch_area: WatchArea
    area: PaneArea
    completions: CompletionList
    hint: Static
    results: ResultsLog
    command_line: CommandLine
    prompt: Static
    hidden_mounted: bool = field(default=False)

    @classmethod
    def make(
        cls,
        members: Members,
        history: History,
        used: Callable[[], frozenset[tuple[str, int]]],
        on_key: Callable[[str], None],
        on_space: Callable[[RowView | None, str], None],
    ) -> Panes:
        """The panes of a console on ``members``: ``used`` gives the indices completion
        offers, ``on_key`` takes a key the table has no use for (the start of a typed
        line), ``on_space`` is the table's Space (both handed over as they are read)."""
        trends: Callable[[str], TrendStore] = members.trend_store
        cell = members.cell_mode
        table = WatchTable(
            trends,
            on_key,
            on_space,
            [(state.name, state.colour) for state in members.states.values()] if cell else (),
            id="watch",
        )
        frame_log = FrameLog(id="log")
        if cell:
            frame_log.target_width = max(len(terminal_safe(n)) for n in members.cell.names)
        io_panel = IoPanel(lambda var: members.toggles.busy(var), id="io")
        command_line = CommandLine(history, used, id="command", placeholder=placeholder_for(None))
        watch_area = WatchArea(table, io_panel, id="watch-area")
        results = ResultsLog(id="results")
        return cls(
            status_bar=StatusBar(id="status", served=members.cell.where is Where.SERVED),
            table=table,
            table_filter=TableFilter(table, id="table-filter"),
            trend_view=TrendView(trends, id="trend"),
            row_detail=RowDetail(id="detail"),
            frame_log=frame_log,
            log_filter=FilterLine(
                frame_log, CELL_FILTER_HINT if cell else FILTER_HINT, id="log-filter"
            ),
            io_panel=io_panel,
            watch_area=watch_area,
            area=PaneArea(watch_area, frame_log, results, id="panes"),
            completions=CompletionList(id="completions"),
            hint=Static(id="hint"),
            results=results,
            command_line=command_line,
            prompt=Static(id="prompt"),
        )

    def shown_at_start(self, cell_mode: bool) -> list[Widget]:
        """The panes of the first screen, in order (a cell's prompt names the target a
        line without @NAME goes to)."""
        command: Widget = self.command_line
        if cell_mode:
            command = Horizontal(self.prompt, self.command_line, id="command-row")
        return [self.status_bar, self.area, command]

    def mount_hidden(self, screen: Screen[None]) -> list[AwaitMount]:
        """The panes nobody sees at start (the filter lines, the trend, the detail, the
        completions, the hint), in their places: mounted once the first screen is
        painted, which they are not on, or at once by a key that opens one before that.
        Returns what to await for them to be mounted (nothing once they are)."""
        if self.hidden_mounted:
            return []
        self.hidden_mounted = True
        area = self.area
        return [
            area.mount(self.table_filter, after=self.watch_area),
            area.mount(self.log_filter, self.trend_view, self.row_detail, after=self.frame_log),
            area.mount(self.completions),  # docked: its place among them is no matter
            screen.mount(self.hint, after=area),
        ]

    @property
    def view_open(self) -> bool:
        """A view opened on a row (the detail, the trend) is in the frame log's place."""
        return self.row_detail.is_open or self.trend_view.has_class("-open")

    def in_focus_order(self) -> list[Widget]:
        """The panes F6 goes through, in order: the ones shown."""
        shown: list[Widget] = [self.command_line, self.table]
        if self.io_panel.display:
            shown.append(self.io_panel)
        if self.trend_view.has_class("-open"):
            shown.append(self.trend_view)
        elif not self.row_detail.is_open and self.frame_log.display:
            shown.append(self.frame_log)  # the detail takes no focus: the arrows stay the
            # table's; a short terminal shows no log
        return shown

    def refresh(
        self, members: Members, running: tuple[str, float, int] | None, rate: float
    ) -> None:
        """The table, the grid, the trend, the detail and the status line, from what the
        members hold now (``running``: the line running; ``rate``: frames a second)."""
        table, now = self.table, time.monotonic()
        if members.cell_mode and table.io_target != members.cell.current:
            table.io_target = members.cell.current  # the grid shows the current's IO
            table.set_hide_io(self.io_panel.display)
        table.refresh_rows(members.row_groups(), members.take_removed(), now)
        self.redraw_trend()
        self.detail_follows_cursor()
        self.io_panel.refresh_rows(members.rows, now)
        self.watch_area.share_width()  # the grid beside the table only while both fit
        status = members.status
        if members.cell_mode:
            self.status_bar.show_cell(members.badges(), running)
        elif status is not None:  # for its width; repainted if changed
            waiting = members.engine.outbox.waiting_since
            self.status_bar.show(status, waiting, rate, running=running)

    def detail_follows_cursor(self) -> None:
        """The open detail follows the table's cursor and the polls."""
        if self.row_detail.is_open:
            self.row_detail.show_row(self.table.cursor_view(), time.monotonic())

    def redraw_trend(self) -> None:
        """At the table's refresh rate: the open view follows its row's field choice."""
        view = self.trend_view
        if view.has_class("-open") and view.var is not None:
            view.fields = [self.table.field_of((t, v)) for t, v, _ in view.series]
            view.redraw()
