"""One test per private Textual hook in ``rac_console.tui.compat``: each fails when
Textual renames the private thing or it stops doing what the console relies on."""

from __future__ import annotations

import gc
import weakref
from typing import ClassVar

from rich.segment import Segment
from rich.text import Text
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.message import Message
from textual.strip import Strip
from textual.widgets import Footer, Input, Log, RichLog

from rac_console.tui import compat


def test_event_clock_is_the_clock_messages_are_stamped_with() -> None:
    before = compat.event_clock()
    message = Message()
    after = compat.event_clock()
    assert before <= message.time <= after


class Keyed(Input):
    BINDINGS: ClassVar[list[BindingType]] = [Binding("ctrl+k", "mine", "Mine")]


def test_key_bindings_are_the_widgets_own_merged_bindings() -> None:
    field = Keyed()
    assert [b.action for b in compat.key_bindings(field, "ctrl+k")] == ["mine"]
    assert [b.action for b in compat.key_bindings(field, "enter")] == ["submit"]  # Input's
    assert list(compat.key_bindings(field, "f12")) == []


class Suggesting(App[None]):
    def compose(self) -> ComposeResult:
        from textual.suggester import SuggestFromList

        yield Input(suggester=SuggestFromList(["get I 1"]))


async def test_input_suggestion_is_the_grey_text_shown() -> None:
    app = Suggesting()
    async with app.run_test() as pilot:
        field = app.query_one(Input)
        assert compat.input_suggestion(field) == ""
        await pilot.press("g")
        for _ in range(100):
            if compat.input_suggestion(field):
                break
            await pilot.pause()
        assert compat.input_suggestion(field) == "get I 1"


class Footed(App[None]):
    BINDINGS: ClassVar[list[BindingType]] = [Binding("f2", "bell", "Ring")]

    def compose(self) -> ComposeResult:
        yield Footer(compact=True)


async def test_footer_keys_are_found_and_read_and_the_footer_says_it_is_ready() -> None:
    app = Footed()
    async with app.run_test() as pilot:
        footer = app.query_one(Footer)
        for _ in range(100):
            if compat.footer_ready(footer) and footer.children:
                break
            await pilot.pause()
        assert compat.footer_ready(footer)
        texts = [compat.footer_key_text(child) for child in footer.children]
        assert "f2 Ring" in texts
        assert compat.footer_key_text(footer) is None  # not a key
        assert any(compat.is_palette_key(child) for child in footer.children)


class Logged(App[None]):
    def compose(self) -> ComposeResult:
        yield Log()
        yield Measured()
        yield RichLog()


class Measured(compat.InlineWidthLog):
    asked: ClassVar[list[list[str]]] = []

    def lines_width(self, lines: list[str]) -> int:
        self.asked.append(lines)
        return 77


async def test_the_log_width_is_measured_by_the_subclass_without_a_thread() -> None:
    app = Logged()
    async with app.run_test() as pilot:
        log = app.query_one(Measured)
        log.write_lines(["abc", "de"])
        assert Measured.asked == [["abc", "de"]]
        assert log.virtual_size.width == 77  # at once: no worker, no call back
        assert not [w for w in app.workers if w.node is log]
        await pilot.pause()


async def test_forgetting_drawn_lines_styles_them_again() -> None:
    app = Logged()
    async with app.run_test() as pilot:
        log = app.query_one(Log)
        log.write_line("one")
        await pilot.pause()
        log._render_line_cache[0] = Strip([Segment("stale")], 5)  # as if drawn before
        assert log.render_line(0).text.startswith("stale")
        compat.forget_drawn_lines(log)
        assert log.render_line(0).text.startswith("one")


class Early(RichLog):
    written: ClassVar[list[bool]] = []

    def write(self, content: object, *args: object, **kwargs: object) -> Early:
        self.written.append(compat.rich_log_sized(self))
        return super().write(content, *args, **kwargs)  # type: ignore[arg-type]


class Sizing(App[None]):
    def compose(self) -> ComposeResult:
        log = Early()
        log.write(Text("before any size"))
        yield log


async def test_a_rich_log_writes_again_what_came_before_its_size() -> None:
    app = Sizing()
    async with app.run_test() as pilot:
        log = app.query_one(Early)
        for _ in range(100):
            if compat.rich_log_sized(log):
                break
            await pilot.pause()
        assert Early.written == [False, True]  # the deferred write, through write()


def test_forgetting_gone_styles_lets_go_a_style_cache_textual_kept() -> None:
    from textual._styles_cache import StylesCache
    from textual.color import Color

    cache = StylesCache()
    cache.get_inner_outer(Color(0, 0, 0), Color(10, 20, 30))  # as a widget's paint does
    drawn = weakref.ref(cache)
    del cache
    gc.collect()
    assert drawn() is not None  # kept by the lru_cache on the method, its widget gone
    compat.forget_gone_styles()
    gc.collect()
    assert drawn() is None


def test_forgetting_split_segments_empties_what_rich_kept_of_a_cut() -> None:
    compat.forget_split_segments()
    Strip([Segment("12:00:00.000 ← 0,3,1↵")], 21).crop(0, 15)  # cut inside the arrow's text
    assert Segment._split_cells.cache_info().currsize > 0  # Rich kept the cut
    compat.forget_split_segments()
    assert Segment._split_cells.cache_info().currsize == 0


async def test_limited_a_rich_log_keeps_that_many_lines_as_drawn() -> None:
    app = Logged()
    async with app.run_test(size=(40, 30)) as pilot:
        log = app.query_one(RichLog)
        compat.limit_drawn_lines(log, 5)
        for n in range(20):
            log.write(f"line {n}")
        await pilot.pause()
        for y in range(20):
            log._render_line(y, 0, 30)  # each drawn
        assert len(log._line_cache) == 5
