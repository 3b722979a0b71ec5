"""Every key of the console, as data: the console screen's and each pane's bindings.

The widgets take their ``BINDINGS`` from here, the help screen reads them back from the
widgets, and the footer shows them: a key is declared once, in this module. A binding's
``tooltip`` is the help screen's line for it; its ``id`` is how the help orders them.
Actions named ``screen.…`` run on the console screen, whichever pane has the focus.
"""

from __future__ import annotations

from textual.binding import Binding, BindingType

PAUSE_HELP = "Pause or resume polling"
PANES_HELP = "Next or previous pane: command line, table, I/O grid, frame log"
FREEZE_HELP = "Freeze the log's scrolling, or follow new frames again"
HISTORY_HELP = "Walk the history (kept across restarts)"
#: The help's line for Tab and Shift+Tab in a pane (one line for both: the same text).
PANE_KEYS = "Next or previous pane"


def pane_bindings(pane: str) -> list[Binding]:
    """Tab and Shift+Tab in ``pane`` (``log``, ``row``, ``trend``): to the next or the
    previous pane, off the footer."""
    return [
        Binding(
            "tab",
            "screen.focus_pane(1)",
            "Next pane",
            tooltip=PANE_KEYS,
            show=False,
            id=f"{pane}-next-pane",
        ),
        Binding(
            "shift+tab",
            "screen.focus_pane(-1)",
            "Previous pane",
            tooltip=PANE_KEYS,
            show=False,
            id=f"{pane}-prev-pane",
        ),
    ]


#: The console's own keys, from any pane: in the footer in this order, after the focused
#: pane's keys, as many as fit.
CONSOLE: list[BindingType] = [
    # First, where the app's own Ctrl+Q stands (Textual declares it before ours).
    Binding("ctrl+q", "app.quit", "Quit", id="quit", priority=True),
    # In the footer in this order, after the focused pane's keys, as many as fit.
    Binding(
        "escape",
        "cancel_command",
        "Cancel command",
        tooltip="Cancel the running line, and the lines typed behind it",
        id="cancel-command",
    ),
    Binding("f1", "help", "Help", id="help"),
    # A cell's: shown only with more than one target (check_action).
    Binding(
        "f8",
        "next_target",
        "Next target",
        tooltip="A cell: use the next target (lines without @NAME go to it)",
        id="next-target",
    ),
    # Priority: taken as the key arrives, so the keys typed right after it go to the
    # new pane (without it they were already on their way to the old one).
    Binding(
        "f6",
        "focus_pane(1)",
        "Next pane",
        tooltip=PANES_HELP,
        id="next-pane",
        priority=True,
    ),
    # F2 and F4 say what they will do: check_action shows one of each pair.
    # The tooltip is the help screen's line (one for both keys of a pair).
    Binding("f2", "toggle_polling", "Pause polls", tooltip=PAUSE_HELP, id="toggle-polling"),
    Binding(
        "f2",
        "toggle_polling('resume')",
        "Resume polls",
        tooltip=PAUSE_HELP,
        id="resume-polling",
    ),
    Binding("f4", "toggle_scroll", "Freeze log", tooltip=FREEZE_HELP, id="toggle-scroll"),
    Binding("f4", "toggle_scroll('follow')", "Follow log", tooltip=FREEZE_HELP, id="follow-log"),
    Binding(
        "f5",
        "toggle_io_grid",
        "I/O grid",
        tooltip="Show or hide the I/O grid: watched IO bits as words",
        id="toggle-io-grid",
    ),
    Binding(
        "f3",
        "toggle_poll_frames",
        "Poll frames",
        tooltip="Show or hide poll frames in the log",
        id="toggle-poll-frames",
    ),
    Binding(
        "f7",
        "toggle_hex",
        "Hex view",
        tooltip="Show or hide each frame's bytes in hex in the log",
        id="toggle-hex",
    ),
    Binding("ctrl+l", "clear_log", "Clear log", id="clear-log"),
    Binding(
        "shift+f6",
        "focus_pane(-1)",
        "Previous pane",
        tooltip=PANES_HELP,
        show=False,
        id="previous-pane",
        priority=True,
    ),
]

#: The keys that work over every screen (the app's): Ctrl+C cancels the running line
#: whatever is shown, a write's question included.
APP: list[BindingType] = [
    # Priority: before the command line's copy, which took it and did nothing. It
    # cancels as Esc does, from any pane, as in the REPL and the CLI.
    Binding(
        "ctrl+c",
        "interrupt",
        "Cancel command",
        tooltip="Cancel the running line, as Esc does (nothing running: it says Ctrl+Q quits)",
        show=False,
        id="interrupt",
        priority=True,
    ),
]

#: The command line's keys.
COMMAND_LINE: list[BindingType] = [
    # Enter typed while the console starts, before the terminal is in raw mode, comes as
    # a line feed: it runs the line as Enter does.
    Binding("ctrl+j", "submit", "Run the line", show=False, id="submit-line-feed"),
    # The tooltip is the help screen's line (Up and Down share one).
    Binding(
        "tab",
        "complete",
        "Complete",
        tooltip="Complete the command, type, index or on/off; several: listed with help",
        id="complete",
    ),
    Binding(
        "up",
        "history(-1)",
        "History back",
        tooltip=HISTORY_HELP,
        show=False,
        id="history-back",
    ),
    Binding(
        "down",
        "history(1)",
        "History forward",
        tooltip=HISTORY_HELP,
        show=False,
        id="history-forward",
    ),
]

#: A filter line's keys (the table's and the log's).
FILTER_LINE: list[BindingType] = [
    Binding("escape", "clear", "Clear filter", id="filter-clear"),
    Binding("enter", "done", "Keep filter", id="filter-done"),
]

#: The frame log's keys.
FRAME_LOG: list[BindingType] = [
    Binding("escape", "screen.focus_command_line", "Command line", id="log-leave"),
    # Priority: the filter line opens as the key arrives, so the keys typed right
    # after it go there (the log takes no other printable key).
    Binding("slash", "screen.filter_frames", "Filter", id="log-filter", priority=True),
    Binding("t", "screen.toggle_frame_times", "Frame times", id="log-frame-times"),
    *pane_bindings("log"),
]

#: The I/O grid's keys.
IO_PANEL: list[BindingType] = [
    # One entry in the help: ←→↑↓  Move the cursor.
    Binding("left", "move(-1, 0)", "Move the cursor", key_display="←", show=False, id="io-left"),
    Binding("right", "move(1, 0)", "Move the cursor", key_display="→", show=False, id="io-right"),
    Binding("up", "move(0, -1)", "Move the cursor", key_display="↑", show=False, id="io-up"),
    Binding("down", "move(0, 1)", "Move the cursor", key_display="↓", show=False, id="io-down"),
    Binding("space", "toggle_bit", "Toggle bit", id="io-toggle-bit"),
    Binding("escape", "screen.focus_command_line", "Command line", id="io-leave"),
]

#: The trend view's keys.
TREND_VIEW: list[BindingType] = [
    Binding("w", "cycle_window", "Window", id="trend-window"),
    Binding("f", "cycle_field", "Trend field", id="trend-field"),
    Binding("t", "close", "Close trend", id="trend-close"),
    Binding("escape", "close", "Close trend", show=False, id="trend-escape"),
    *pane_bindings("trend"),
]

#: The watch table's keys: in the footer in this order, as many as fit.
WATCH_TABLE: list[BindingType] = [
    # In the footer in this order, as many as fit.
    Binding(
        "enter",
        "row('put')",
        "Edit value",
        tooltip="Put the row's value on the command line, to edit and write",
        id="row-put",
    ),
    Binding(
        "d",
        "screen.toggle_detail",
        "Details",
        tooltip="The row under the cursor in full, a field a line (d again closes)",
        id="row-detail",
    ),
    Binding("space", "row('toggle')", "Toggle", id="row-toggle"),
    Binding("delete", "row('unwatch')", "Unwatch", id="row-unwatch"),
    Binding("slash", "row('filter')", "Filter", id="row-filter"),
    Binding("t", "row('trend')", "Trend", id="row-trend"),
    Binding(
        "T",
        "row('overlay')",
        "Overlay trend",
        tooltip="Add the row to the open trend (a cell: several targets on one time axis)",
        id="row-overlay",
    ),
    Binding("s", "cycle_sort", "Sort", id="row-sort"),
    Binding(
        "f",
        "cycle_field",
        "Trend field",
        tooltip="Trend the next field (X, Y, Z…) of a position row",
        id="row-field",
    ),
    # Esc backs out a step at a time: the view opened on a row (shown while one is, see
    # the console's check_action), then to the command line.
    Binding(
        "escape",
        "screen.close_view",
        "Close view",
        tooltip="Close the detail or the trend (the table keeps the keys); again: to the "
        "command line",
        id="row-close-view",
    ),
    Binding("escape", "screen.focus_command_line", "Command line", id="row-leave"),
    *pane_bindings("row"),
]

#: The help screen's keys (F1 closes it as it opened it).
HELP_SCREEN: list[BindingType] = [
    Binding("escape", "close", "Close help", id="help-close"),
    Binding("f1", "close", "Close help", show=False, id="help-f1"),
    Binding("up", "scroll(-1)", "Scroll up", show=False, id="help-up"),
    Binding("down", "scroll(1)", "Scroll down", show=False, id="help-down"),
    Binding("pageup", "page(-1)", "Page up", show=False, id="help-page-up"),
    Binding("pagedown", "page(1)", "Page down", show=False, id="help-page-down"),
]


def key_for(action: str, bindings: list[BindingType] = CONSOLE) -> str | None:
    """The key bound to ``action`` among ``bindings`` (the console's by default), as
    printed on the keyboard (``F2``, ``Ctrl+L``); None when no key runs it."""
    from ..present.help_text import key_label

    for binding in Binding.make_bindings(bindings):
        if binding.action == action:
            return key_label(binding.key_display or binding.key)
    return None
