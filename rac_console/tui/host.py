"""What the console's parts need of the app that holds them, as a protocol.

The palette, the table's and the log's keys and the settings keeper are written
against :class:`ConsoleHost`, not against the app: they import this module, the app
imports them, and no import goes back (``lint-imports`` keeps ``tui/`` free of circles).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import TYPE_CHECKING, Any, Protocol, cast

from textual.app import App, SystemCommand
from textual.screen import Screen
from textual.timer import Timer
from textual.widget import Widget

if TYPE_CHECKING:  # for the type checker only: the parts import this module
    from ..commands.language import Command
    from ..commands.policy import TargetProfile
    from ..engine import Engine, Feedback, Status
    from ..engine.cell import Cell
    from ..present.toggles import PendingToggles
    from ..present.trends import TrendStore
    from .cell_state import MemberState
    from .command_line import CommandLine
    from .file_writes import FileWrites
    from .filter_line import FilterLine
    from .frame_log import FrameLog
    from .io_panel import IoPanel
    from .row_detail import RowDetail
    from .trend_view import TrendView
    from .watch_table import TableFilter, WatchTable


class ConsoleHost(Protocol):
    """The app as its parts see it: the cell, the panes, and a few verbs."""

    cell: Cell
    cell_mode: bool  # more than one target

    @property
    def engine(self) -> Engine:
        """The current target's engine."""

    @property
    def status(self) -> Status | None:
        """The current target's status."""

    def state_of(self, name: str | None) -> MemberState:
        """A target's state by name (None, or a name not in the cell: the current one)."""

    def trend_store(self, name: str) -> TrendStore: ...

    profile_names: tuple[str, ...]  # the config file's targets, for connect NAME

    @property
    def profiles(self) -> Mapping[str, TargetProfile]: ...

    command_line: CommandLine
    table: WatchTable
    table_filter: TableFilter
    frame_log: FrameLog
    log_filter: FilterLine
    io_panel: IoPanel
    trend_view: TrendView
    row_detail: RowDetail

    @property
    def trends(self) -> TrendStore: ...
    @property
    def toggles(self) -> PendingToggles: ...

    files: FileWrites  # file writes, off the screen's loop

    # Textual's, as the app has them.
    @property
    def screen(self) -> Screen[object]: ...
    @property
    def focused(self) -> Widget | None: ...
    @property
    def title(self) -> str: ...

    theme: str

    @property
    def available_themes(self) -> Mapping[str, object]: ...
    def set_timer(self, delay: float, callback: Callable[[], object]) -> Timer: ...
    def push_screen(self, screen: Any, callback: Any = None) -> Any: ...
    def notify(
        self, message: str, *, title: str = "", severity: Any = "information", markup: bool = True
    ) -> None: ...
    def export_screenshot(self) -> str: ...
    def get_system_commands(self, screen: Screen[Any]) -> Iterable[SystemCommand]: ...

    # The console's verbs.
    def show(self, feedback: Feedback) -> None:
        """A message, an outcome or a UI step, in the results."""

    def submit_line(
        self, line: str, command: Command | None = None, target: str | None = None
    ) -> int:
        """Run a line as if typed (echoed, queued, cancelled by Esc), or ``command``
        shown as ``line`` on ``target`` (None: the current one): its sequence."""

    def may_ask(self, line: str) -> bool:
        """Whether ``line``, run now, may stop to ask before it writes."""

    def hold_keys(self, seq: int, queued: bool) -> None:
        """Hold the keys typed after line ``seq`` until it asked or ended."""

    def refresh_table(self) -> None:
        """The table, the grid, the trend, the detail and the status line, up to date."""

    def action_toggle_polling(self, _shown: str = "") -> None: ...
    def action_toggle_poll_frames(self) -> None: ...
    def action_toggle_scroll(self, _shown: str = "") -> None: ...
    def action_toggle_io_grid(self) -> None: ...
    def action_clear_log(self) -> None: ...
    def action_toggle_hex(self) -> None: ...
    def action_toggle_detail(self) -> None: ...
    def action_help(self) -> None: ...
    def put_on_command_line(self, text: str) -> None: ...
    def mount_hidden_panes(self) -> list[Any]:
        """The panes hidden at start, mounted (before one of them opens)."""


def host_of(app: App[Any]) -> ConsoleHost:
    """The app a palette provider runs in, as its host (Textual types it as any app)."""
    return cast(ConsoleHost, app)
