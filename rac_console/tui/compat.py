"""Every private Textual (and Rich) hook the console uses, each in one small function here.

Textual gives no promise about names with a leading underscore. Keeping them in one
place means an upgrade is checked here, and ``tests/test_tui_compat.py`` fails (one test
per hook) when a hook stops existing or stops doing what the console relies on. Each
was checked against Textual 8.2.8, and CI runs those tests again on the lowest Textual
pyproject allows (``textual>=6.2``: ``scripts/lowest-tests``); the rest of ``tui/``
uses public Textual only.
"""

from __future__ import annotations

from collections.abc import Sequence

from rich.cells import cell_len
from rich.segment import Segment
from rich.style import Style
from textual import _time
from textual._styles_cache import StylesCache
from textual.binding import Binding
from textual.dom import DOMNode
from textual.strip import Strip
from textual.widget import Widget
from textual.widgets import Footer, Input, Log, RichLog
from textual.widgets._footer import FooterKey

#: The Textual version these hooks were last checked against.
CHECKED_WITH = "8.2.8"


def event_clock() -> float:
    """Now, on the clock Textual stamps every message's ``time`` with (``_time.get_time``:
    monotonic, or ``perf_counter`` on Windows), so a key's ``time`` compares with it.
    Checked with Textual 8.2.8."""
    return _time.get_time()


def key_bindings(node: DOMNode, key: str) -> Sequence[Binding]:
    """The bindings ``node`` itself declares for ``key`` (its merged ``_bindings`` map,
    without the app's or its ancestors'): a widget that runs its own bindings as keys
    come, in key order. Checked with Textual 8.2.8."""
    return node._bindings.key_to_bindings.get(key, ())


def input_suggestion(field: Input) -> str:
    """The grey suggestion an :class:`Input` shows after its value (its ``_suggestion``
    reactive; empty when none). Checked with Textual 8.2.8."""
    return field._suggestion


def footer_key_text(widget: Widget) -> str | None:
    """A footer key's ``key description`` as the compact footer draws it; None for any
    other widget (``FooterKey`` lives in the private ``textual.widgets._footer``).
    Checked with Textual 8.2.8."""
    if not isinstance(widget, FooterKey):
        return None
    if widget.description:
        return f"{widget.key_display} {widget.description}"
    return widget.key_display


def is_palette_key(widget: Widget) -> bool:
    """Whether a footer widget is the palette's key (drawn last, at the right)."""
    return isinstance(widget, FooterKey) and widget.has_class("-command-palette")


def footer_ready(footer: Footer) -> bool:
    """Whether the footer has had its bindings once (its ``_bindings_ready``): before,
    a recompose draws nothing. Checked with Textual 8.2.8."""
    return footer._bindings_ready


def rich_log_sized(log: RichLog) -> bool:
    """Whether a :class:`RichLog` knows its width yet (its ``_size_known``): before, it
    keeps what is written and, at its first size, writes it again through ``write``.
    Checked with Textual 8.2.8."""
    return log._size_known


def forget_drawn_lines(log: Log) -> None:
    """Make a :class:`Log` style its lines again at the next paint (it caches each line
    drawn in ``_render_line_cache``): the highlighter's rules changed, not the lines.
    Checked with Textual 8.2.8."""
    log._render_line_cache.clear()
    log.refresh()


class InlineWidthLog(Log):
    """A :class:`Log` that measures the width of the lines it is given here and now.

    Textual's ``Log.write_lines`` calls ``_update_size``, a thread worker measuring
    every new line's cells, then ``_update_maximum_width`` back on the loop: one thread
    per write, and a call into a loop that may be closing. Subclasses say how wide lines
    are with :meth:`lines_width`, which can be much cheaper for lines they know.
    Checked with Textual 8.2.8.
    """

    def lines_width(self, lines: list[str]) -> int:
        """The widest of ``lines`` in cells."""
        return max(cell_len(line) for line in lines)

    def _render_line(self, y: int, scroll_x: int, width: int) -> Strip:
        """Log's line, cropped to the view, with "…" where it goes on past either
        edge: a frame cut at the right must not end in a number that reads as whole
        (``… 0.`` for ``0.30 ms``). Textual's private ``Log._render_line`` (8.2.8)."""
        strip: Strip = super()._render_line(y, scroll_x, width)
        drawn, width = width, min(width, self.scrollable_content_region.width or width)
        if y >= len(self._lines) or width < 2:
            return strip
        full = self._render_line_strip(y, self.rich_style).cell_length
        cut_right, cut_left = full > scroll_x + width, scroll_x > 0 and full > 0
        if not (cut_right or cut_left):
            return strip
        mark = Strip([Segment("…", self.rich_style + Style(dim=True))], 1)
        start, end = (1 if cut_left else 0), (width - 1 if cut_right else width)
        parts = [mark] if cut_left else []
        parts.append(strip.crop(start, end))
        if cut_right:
            parts.append(mark)
        return Strip.join(parts).extend_cell_length(drawn, self.rich_style)

    def _update_size(self, updates: int, lines: list[str]) -> None:  # type: ignore[override]
        if lines:
            self._update_maximum_width(updates, self.lines_width(lines))


def forget_closed_watchers(node: DOMNode) -> None:
    """Drop the watchers of ``node``'s reactives whose watching node has closed.

    Textual keeps each watcher (``data_bind``, ``watch``) in the watched object's
    ``__watchers`` until that reactive next changes; a footer's keys are data-bound to
    its ``compact``, which never changes, so every recompose (each change of the keys
    shown, at every line run) left its old keys held: about 430 KB a line, for good.
    Checked with Textual 8.2.8."""
    watchers: dict[str, list[tuple[DOMNode, object]]] = getattr(node, "__watchers", {})
    for watching in watchers.values():
        watching[:] = [(n, call) for n, call in watching if not (n._closing or n._closed)]


def forget_gone_styles() -> None:
    """Let go of the style caches of widgets gone.

    Textual's ``StylesCache.get_inner_outer`` is an ``lru_cache(1024)`` on a method, so
    it keeps up to 1,024 ``StylesCache`` objects alive, each with the lines its widget
    drew (about 4 KB), long after the widget was removed: the footer's keys go at every
    line run, so it filled with theirs (4 MB). It is a cache of two colours: emptied,
    the widgets on screen fill it again at the next paint. Checked with Textual 8.2.8."""
    StylesCache.get_inner_outer.cache_clear()


def forget_split_segments() -> None:
    """Empty Rich's cache of segments cut at a cell (``Segment._split_cells``).

    Rich keeps every cut of a segment that holds a character outside its single-cell
    fast path (the frame log's ``←`` and ``↵``) in an ``lru_cache`` of 16,384; a log's
    lines cut at the view's edge are new each time and never looked up again (no hit
    in a shift's worth), about 540 B each: 9 MB once full. Checked with Rich 15.0.0
    (and 13.3.3, the lowest pyproject allows)."""
    Segment._split_cells.cache_clear()


def limit_drawn_lines(log: RichLog, lines: int) -> None:
    """Keep at most ``lines`` of a :class:`RichLog`'s lines as drawn (its
    ``_line_cache``, 1,024): keyed by each line's number since the log began, it held
    a copy of each of the last 1,024 lines shown (about 5 KB each with its caches),
    however few the pane shows. Checked with Textual 8.2.8."""
    log._line_cache.maxsize = lines
