"""The help screen (F1, or ``?`` on an empty command line): keys, commands, status line.

The keys are read from the widgets' ``BINDINGS`` when the screen opens, the commands
from the registry and the figures from :mod:`rac_console.present.help_text`, so the
help says what the console does now. An input at the top filters it as you type.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import ClassVar

from rich.console import Group, RenderableType
from rich.table import Table
from rich.text import Text
from textual import on
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import VerticalScroll
from textual.screen import Screen
from textual.widgets import Input, Static

from ..present.help_text import (
    HelpSection,
    KeyGroup,
    filter_sections,
    key_label,
    plain_lines,
)
from . import keys
from .command_line import CommandLine
from .filter_line import FilterLine
from .frame_log import FrameLog
from .io_panel import IoPanel
from .trend_view import TrendView
from .watch_table import WatchTable

#: The widest a key or a command's usage runs before it wraps (80 columns leave the
#: description 45).
TERM_WIDTH = 24


#: Where keys are read from: a widget's class (its own and its console parents'
#: bindings), or a list of bindings (the console screen's, :data:`keys.CONSOLE`).
KeySource = type | list[BindingType]


def bindings_of(source: KeySource) -> list[Binding]:
    """The bindings a class declares itself (not those it inherits), or the list's."""
    declared: Iterable[BindingType] = (
        source if isinstance(source, list) else source.__dict__.get("BINDINGS", ())
    )
    return list(Binding.make_bindings(declared))


def _sources(source: KeySource) -> list[KeySource]:
    """The console's classes ``source`` is made of, or the list alone."""
    if isinstance(source, list):
        return [source]
    return [klass for klass in source.__mro__ if klass.__module__.startswith("rac_console.")]


def key_of(source: KeySource, action: str) -> str | None:
    """The key bound to ``action`` on ``source``, as printed on the keyboard (``F2``,
    ``Ctrl+L``); None when no key runs it."""
    for part in _sources(source):
        if (key := keys.key_for(action, list(bindings_of(part)))) is not None:
            return key
    return None


#: Keys only a cell has (more than one target): in the help only there.
CELL_KEYS = frozenset({"next-target", "row-overlay"})


def _pairs(
    source: KeySource, only: Sequence[str] | None = None, without: frozenset[str] = frozenset()
) -> list[tuple[str, str]]:
    """The keys of ``cls`` and of the console's classes it inherits from (not those of
    Textual's), labelled, with their descriptions; a key given twice counts once.
    With ``only`` (binding ids), just those, in that order; never those ``without``."""
    pairs: dict[str, str] = {}
    found: dict[str, tuple[str, str]] = {}
    for part in _sources(source):
        for binding in bindings_of(part):
            if binding.id in without:
                continue
            key = key_label(binding.key_display or binding.key)
            text = binding.tooltip or binding.description
            if only is None:
                pairs.setdefault(key, text)
            elif binding.id is not None and binding.id in only:
                found.setdefault(binding.id, (key, text))
    if only is not None:
        return [found[id_] for id_ in only if id_ in found]
    return list(pairs.items())


#: The console's own keys in the help, in this order: help and palette, moving about,
#: what is shown, then leaving (the footer has its own order: the most used first).
APP_KEYS = (
    "help",
    "next-pane",
    "previous-pane",
    "toggle-polling",
    "toggle-poll-frames",
    "toggle-scroll",
    "toggle-io-grid",
    "toggle-hex",
    "clear-log",
    "next-target",
    "interrupt",
    "quit",
)


def console_key_groups(app_class: type[App[int]], cell: bool = False) -> list[KeyGroup]:
    """The console's keys, read from :mod:`.keys` and its panes' bindings, labelled
    as on the keyboard: the command line's first, then the table's, the other panes',
    and last the keys that work anywhere (a cell's own keys only in a cell); ``app_class``
    gives the palette's key."""
    without = frozenset() if cell else CELL_KEYS
    pane = key_of(keys.CONSOLE, "focus_pane(1)") or "F6"
    grid = key_of(keys.CONSOLE, "toggle_io_grid") or "F5"
    trend = key_of(WatchTable, "row('trend')") or "t"
    row_filter = key_of(WatchTable, "row('filter')") or "/"
    anywhere = _pairs([*keys.CONSOLE, *keys.APP], APP_KEYS, without)
    palette = (key_label(app_class.COMMAND_PALETTE_BINDING), "Command palette")
    return [
        (
            "command line",
            [
                ("Enter", "Run the line"),
                *_pairs(CommandLine, without=frozenset({"submit-line-feed"})),  # Enter's
                ("Right", "Accept the grey suggestion from history (at the end of the line)"),
                ("?", "Help (on an empty line)"),
                *_pairs(keys.CONSOLE, ("cancel-command",)),
            ],
        ),
        (f"watch table ({pane})", _pairs(WatchTable, without=without)),
        (f"filter line ({row_filter} in the table or the frame log)", _pairs(FilterLine)),
        (f"I/O grid ({grid}, then {pane})", _pairs(IoPanel)),
        (f"frame log ({pane})", _pairs(FrameLog)),
        (f"trend view ({trend} on a row, then {pane})", _pairs(TrendView)),
        ("anywhere", [*anywhere[:1], palette, *anywhere[1:]]),
    ]


def render_sections(sections: Sequence[HelpSection], query: str) -> RenderableType:
    """The sections as a title and a two-column grid each; the query's matches marked."""
    parts: list[RenderableType] = []
    for section in sections:
        if parts:
            parts.append(Text())
        parts.append(Text(section.title, style="bold underline"))
        grid = Table.grid(padding=(0, 2))
        grid.add_column(style="bold", max_width=TERM_WIDTH)
        grid.add_column(ratio=1)
        for entry in section.entries:
            text = Text(entry.text)
            for more in entry.more:
                text.append("\n")
                text.append(more, style="dim")
            term = Text(entry.term)
            if query:
                for cell in (term, text):
                    cell.highlight_words([query], style="reverse", case_sensitive=False)
            grid.add_row(term, text)
        parts.append(grid)
    return Group(*parts)


class HelpScreen(Screen[None]):
    """The help, filtered by the line at its top; Esc (or F1 again) closes it."""

    CSS_PATH = "help_screen.tcss"
    BINDINGS: ClassVar[list[BindingType]] = keys.HELP_SCREEN

    def __init__(self, sections: Sequence[HelpSection]) -> None:
        super().__init__()
        self.sections = list(sections)
        self.matched = 0
        self.total = 0
        self.shown_text = ""  # what the body shows, as plain text

    def compose(self) -> ComposeResult:
        yield Input(placeholder="search the help: a key, a command, a word", id="help-search")
        with VerticalScroll(id="help-body"):
            yield Static(id="help-text")
        yield Static(
            Text.assemble(
                ("Esc", "bold"),
                " closes  ",
                ("Up Down PgUp PgDn", "bold"),
                " scroll  ",
                ("Ctrl+P", "bold"),
                " palette",
            ),
            id="help-keys",
        )

    def on_mount(self) -> None:
        body = self.query_one("#help-body", VerticalScroll)
        body.border_title = "Help: keys, commands, status line"
        body.can_focus = False
        self._show("")
        self.query_one("#help-search", Input).focus()

    @on(Input.Changed, "#help-search")
    def _search(self, event: Input.Changed) -> None:
        event.stop()  # the console's command-line handlers are not for this input
        self._show(event.value)

    @on(Input.Submitted, "#help-search")
    def _keep(self, event: Input.Submitted) -> None:
        event.stop()

    def _show(self, query: str) -> None:
        shown, self.matched, self.total = filter_sections(self.sections, query)
        body = self.query_one("#help-body", VerticalScroll)
        text = self.query_one("#help-text", Static)
        query = query.strip()
        if not query:
            body.border_subtitle = f"{self.total} entries · type to search"
        else:
            lines = "line matches" if self.total == 1 else "lines match"
            body.border_subtitle = f"{self.matched} of {self.total} {lines}"
        if shown:
            text.update(render_sections(shown, query))
            self.shown_text = "\n".join(plain_lines(shown))
        else:
            message = Text.assemble("nothing matches ", (repr(query), "bold"))
            text.update(message)
            self.shown_text = message.plain
        body.scroll_home(animate=False)

    def action_close(self) -> None:
        self.dismiss(None)

    def action_scroll(self, lines: int) -> None:
        self.query_one("#help-body", VerticalScroll).scroll_relative(y=lines, animate=False)

    def action_page(self, step: int) -> None:
        body = self.query_one("#help-body", VerticalScroll)
        if step < 0:
            body.scroll_page_up(animate=False)
        else:
            body.scroll_page_down(animate=False)
