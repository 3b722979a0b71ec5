"""Reading and finding rows (issue 20): a position row whole at any width (``d``: the
row under the cursor, a field a line), new rows brought into view, the palette naming
each target, the help's keys in the order a user looks for them."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from textual import events
from textual.command import CommandPalette
from textual.geometry import Size
from textual.pilot import Pilot
from textual.widgets import DataTable

from rac_console.commands.language import VarRef
from rac_console.commands.policy import TargetProfile, WritePolicy, Writes, parse_allow
from rac_console.engine import Engine, RowView
from rac_console.present.history import History
from rac_console.present.row_detail import columns_for, detail_fields, detail_text, header_text
from rac_console.present.table_cells import CHANGED_DARK
from rac_console.protocol import Variant, kind_of
from rac_console.tui.app import RacConsoleApp
from rac_console.tui.help_screen import console_key_groups
from rac_console.tui.palette_commands import profile_help
from rac_console.tui.watch_table import REVEAL_TRIES
from tests.support.drivers import make_app, pause_polling, type_line, until

P = kind_of("P")
NOW = 1000.0


def p_row(values: list[float], *, stale: bool = False) -> RowView:
    var = VarRef(P, 10)
    status = "TIMEOUT" if stale else "OK"
    return RowView(var, "pick", Variant(P.vt, values), status, stale, NOW - 3, None)


POSE = [350.0, 0.0, 450.5, 180.0, 0.0, -179.25, 5]


# ------------------------------------------------------------------ pure parts


def test_a_position_row_is_a_field_a_line_each_value_whole() -> None:
    row = p_row(POSE)
    assert detail_fields(row) == [
        ("X", "350"),
        ("Y", "0"),
        ("Z", "450.5"),
        ("Rx", "180"),
        ("Ry", "0"),
        ("Rz", "-179.25"),
        ("Fig", "5"),
    ]
    lines = detail_text(row, NOW, height=7).plain.split("\n")
    assert lines == [
        "X        350",
        "Y          0",
        "Z      450.5",
        "Rx       180",
        "Ry         0",
        "Rz   -179.25",
        "Fig        5",
    ]


def test_fields_go_in_columns_of_three_when_the_lines_do_not_fit() -> None:
    assert columns_for(7, 7) == 1
    assert columns_for(7, 6) == 3  # X Y Z | Rx Ry Rz | Fig
    assert columns_for(10, 4) == 4  # a T: X Y Z | Ox Oy Oz | Ax Ay Az | Fig
    assert columns_for(8, 2) == 4
    lines = detail_text(p_row(POSE), NOW, height=4).plain.split("\n")
    assert len(lines) == 3
    assert lines[0].split() == ["X", "350", "Rx", "180", "Fig", "5"]
    assert lines[2].split() == ["Z", "450.5", "Rz", "-179.25"]


def test_the_header_says_what_the_table_says_and_a_changed_field_stands_out() -> None:
    row = p_row(POSE)
    assert header_text(row, NOW).plain == "P10  pick  OK  changed 3s ago  VT_R4|VT_ARRAY"
    text = detail_text(row, NOW, height=7, changed={2})
    z_line = text.plain.split("\n")[2]
    start = text.plain.index(z_line) + z_line.index("450.5")
    assert any(
        span.style == CHANGED_DARK.value and span.start <= start < span.end for span in text.spans
    )
    stale = p_row(POSE, stale=True)
    assert "TIMEOUT (stale)" in header_text(stale, NOW).plain
    assert "dim italic" in {str(span.style) for span in detail_text(stale, NOW, 7).spans}


def test_other_rows_have_one_value_and_no_value_is_said() -> None:
    io = VarRef(kind_of("IO"), 128)
    assert detail_fields(RowView(io, "", Variant(11, True), "OK", False, NOW, None)) == [
        ("value", "ON")
    ]
    waiting = RowView(VarRef(P, 1), "", None, "WAITING", False, None, None)
    assert detail_fields(waiting) == [("value", "no value yet")]


def test_a_profile_in_the_palette_names_its_address_and_write_mode() -> None:
    policy = WritePolicy(Writes.CONFIRM, (parse_allow("I 100-199"),), "profile cell3")
    profile = TargetProfile("cell3", "10.0.0.5", 5006, "Cell 3 [b]x", "red", policy)
    assert profile_help(profile) == r"LIVE 10.0.0.5:5006 · writes confirm · allow I 100-199"
    assert profile_help(profile, current=True).endswith(" · connected now")
    assert profile_help(None) == "a target profile from the config file"


def test_the_help_lists_the_command_line_then_the_table_then_panes_then_the_app() -> None:
    groups = console_key_groups(RacConsoleApp)
    titles = [title for title, _ in groups]
    assert titles[0] == "command line"
    assert titles[1].startswith("watch table")
    assert titles[-1] == "anywhere"
    command_line = dict(groups[0][1])
    assert "Esc" in command_line and "cancel" in command_line["Esc"].lower()
    assert list(command_line)[:2] == ["Enter", "Tab"]
    table = dict(groups[1][1])
    assert "full" in table["d"]  # the row in full
    anywhere = [key for key, _ in groups[-1][1]]
    assert anywhere[:2] == ["F1", "Ctrl+P"]
    assert anywhere[-2:] == ["Ctrl+C", "Ctrl+Q"]
    assert anywhere.index("F6") < anywhere.index("F2") < anywhere.index("F7")


# ------------------------------------------------------------------ the console


def detail_lines(app: RacConsoleApp) -> list[str]:
    return app.main_screen.panes.row_detail.shown_text.split("\n")


async def watch_ok(pilot: Pilot, line: str, rows: int) -> None:
    app = pilot.app
    assert isinstance(app, RacConsoleApp)
    await type_line(pilot, line)
    await until(
        pilot,
        lambda: (
            app.main_screen.panes.table.row_count == rows
            and all(v.status == "OK" for v in app.main_screen.members.rows.values())
        ),
        f"{rows} rows with values",
    )


@pytest.mark.slow
async def test_d_shows_the_row_under_the_cursor_in_full_at_80_columns(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await watch_ok(pilot, "watch P 1 J 1", 2)
        value = str(app.main_screen.panes.table.get_cell_at((0, 5)))  # type: ignore[arg-type]
        assert "Fig" in value  # the table holds it all, but the screen cuts it
        table = app.main_screen.panes.table
        await until(  # the widths measured once the table's queue runs dry
            pilot,
            lambda: table.virtual_size.width > table.scrollable_content_region.width,
            "the values wider than the table",
        )
        await pilot.press("f6", "d")
        await until(pilot, lambda: app.main_screen.panes.row_detail.is_open, "the detail")
        await until(
            pilot, lambda: "Fig" in app.main_screen.panes.row_detail.shown_text, "the P row"
        )
        assert not app.main_screen.panes.frame_log.display  # in its place; the log keeps collecting
        assert [line.split()[0] for line in detail_lines(app)] == [
            "X",
            "Y",
            "Z",
            "Rx",
            "Ry",
            "Rz",
            "Fig",
        ]
        assert "P1" in str(app.main_screen.panes.row_detail.border_title)
        assert app.focused is app.main_screen.panes.table  # the arrows stay the table's
        await pilot.press("down")
        await until(pilot, lambda: "J8" in app.main_screen.panes.row_detail.shown_text, "the J row")
        assert "J1" in str(app.main_screen.panes.row_detail.border_title)
        await pilot.press("d")
        await until(pilot, lambda: not app.main_screen.panes.row_detail.is_open, "closed")
        assert app.main_screen.panes.frame_log.display


@pytest.mark.slow
async def test_the_detail_and_the_trend_take_turns_in_the_logs_place(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await watch_ok(pilot, "watch P 1", 1)
        await pilot.press("f6", "d")
        await until(pilot, lambda: app.main_screen.panes.row_detail.is_open, "the detail")
        await pilot.press("t")
        await until(pilot, lambda: app.main_screen.panes.trend_view.has_class("-open"), "the trend")
        assert not app.main_screen.panes.row_detail.is_open
        await pilot.press("d")  # the table kept the keys: the detail again
        await until(pilot, lambda: app.main_screen.panes.row_detail.is_open, "the detail again")
        assert not app.main_screen.panes.trend_view.has_class("-open")


@pytest.mark.slow
async def test_rows_added_below_the_view_are_scrolled_to(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await watch_ok(pilot, "watch P 0 J 0 T 0 S 1 I 20", 5)
        await until(pilot, lambda: app.main_screen.panes.table.scroll_y == 0, "at the top")
        await type_line(pilot, "watch I 0-99")
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 104, "the new rows")
        await until(pilot, lambda: app.main_screen.panes.table.scroll_y > 0, "scrolled", timeout=3)
        room = (
            app.main_screen.panes.table.scrollable_content_region.height
            - app.main_screen.panes.table.header_height
        )
        top = round(app.main_screen.panes.table.scroll_y)
        shown = [str(app.main_screen.panes.table.get_row_at(n)[0]) for n in range(top, top + room)]
        assert shown[0] == "I0", shown  # too many to show: the first at the top
        await type_line(pilot, "watch I 300")  # one more: the least scroll shows it
        await until(pilot, lambda: app.main_screen.panes.table.row_count == 105, "one more row")
        last = app.main_screen.panes.table.row_count - 1
        await until(
            pilot,
            lambda: (
                round(app.main_screen.panes.table.scroll_y)
                <= last
                < round(app.main_screen.panes.table.scroll_y) + room
            ),
            "the new row in view",
            timeout=3,
        )


@pytest.mark.slow
async def test_palette_names_each_profiles_target(tmp_path: Path) -> None:
    base = make_app(tmp_path)
    policy = WritePolicy(Writes.CONFIRM, None, "profile cell3")
    cell3 = TargetProfile("cell3", "10.0.0.5", 5006, "Cell 3 — welding", "red", policy)
    engine = Engine(None, timeout=1.0, interval=0.05, profiles={"cell3": cell3})
    app = RacConsoleApp(engine, History(tmp_path / "history"), profile_names=("cell3",))
    del base
    async with app.run_test(size=(100, 40)) as pilot:
        await pilot.press("ctrl+p")
        await until(pilot, lambda: isinstance(app.screen, CommandPalette), "the palette")
        await pilot.press(*"weld")  # the label finds it
        await until(pilot, lambda: "cell3" in palette_text(app), "the hit")
        text = palette_text(app)
        assert "connect cell3  (Cell 3 — welding)" in text
        assert "LIVE 10.0.0.5:5006 · writes confirm" in text
        await pilot.press("escape")


def palette_text(app: RacConsoleApp) -> str:
    from textual.command import CommandList

    options = app.screen.query_one(CommandList).options
    return "\n".join(str(option.prompt) for option in options)


@pytest.mark.slow
@pytest.mark.parametrize("hidden", [("vertical",), ("vertical", "horizontal")])
async def test_rows_are_scrolled_to_before_the_layout_shows_the_scrollbars(
    tmp_path: Path, hidden: tuple[str, ...]
) -> None:
    """The table can have measured its new rows before the layout that follows has
    shown its scrollbars; scrolling to them then did nothing (the thumb, once shown,
    left at the top), or scrolled as if the horizontal scrollbar, to come, took no
    room: a row stayed out of view (a snapshot at 80x24 caught both under load)."""
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        table = app.main_screen.panes.table
        await watch_ok(pilot, "watch J 1 T 1 IO 128-131", 6)
        await pause_polling(pilot)  # no values to come: the table holds still
        await until(  # measured and laid out: the values cut at 80 columns, the rows too many
            pilot,
            lambda: table.show_horizontal_scrollbar and table.max_scroll_y > 0,
            "a scrollbar each way",
        )
        room = table.scrollable_content_region.height - table.header_height
        assert room < 6
        table.scroll_home(animate=False, immediate=True)
        # As in the moment before that layout: the scrollbars the rows and the values
        # call for are not shown yet (the horizontal one would take a row from the view).
        for name in hidden:
            setattr(table, f"show_{name}_scrollbar", False)
        table.reveal_rows(2, 5)
        table.refresh(layout=True)  # the layout that shows them
        await until(pilot, lambda: round(table.scroll_y) == 6 - room, "the new rows in view")
        await until(pilot, lambda: table.show_vertical_scrollbar, "the scrollbar")
        assert table.show_horizontal_scrollbar and round(table.scroll_y) == 6 - room
        assert table.vertical_scrollbar.position == table.scroll_y, "the thumb where the view is"


@pytest.mark.slow
async def test_rows_just_shown_stay_in_view_when_their_values_widen_the_table(
    tmp_path: Path,
) -> None:
    """Rows shown before their values came: the values make the table wider than its
    pane, the horizontal scrollbar takes a line from the view, and the last new row
    went out of view under it (a snapshot at 80x24 caught it under load)."""
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        table = app.main_screen.panes.table
        await watch_ok(pilot, "watch J 1 T 1 IO 128-131", 6)
        await pause_polling(pilot)  # no values to come: the table holds still
        await until(  # measured and laid out: the values cut at 80 columns, the rows too many
            pilot,
            lambda: table.show_horizontal_scrollbar and table.max_scroll_y > 0,
            "a scrollbar each way",
        )
        wide = table.virtual_size
        table.scroll_home(animate=False, immediate=True)
        # The rows as they were before their values came: narrow enough for the pane.
        table.virtual_size = Size(table.scrollable_content_region.width, wide.height)
        table.refresh(layout=True)
        await until(pilot, lambda: not table.show_horizontal_scrollbar, "no scrollbar")
        room = table.scrollable_content_region.height - table.header_height
        table.reveal_rows(2, 5)
        assert round(table.scroll_y) == 6 - room, "the new rows in view"
        table.virtual_size = wide  # the values came
        table.refresh(layout=True)
        await until(pilot, lambda: table.show_horizontal_scrollbar, "the scrollbar")
        await until(
            pilot, lambda: round(table.scroll_y) == 6 - (room - 1), "the new rows in view still"
        )


@pytest.mark.slow
async def test_rows_are_scrolled_to_however_long_the_table_takes_to_measure_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The table measures rows added when its queue runs dry; under load that can be
    after many screen refreshes. The new rows are still brought into view then."""
    app = make_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        table = app.main_screen.panes.table
        await watch_ok(pilot, "watch J 1 T 1", 2)
        held = True
        measure = DataTable._on_idle

        async def busy(self: DataTable[Any], event: Any) -> None:  # no dry queue meanwhile
            if not held:
                await measure(self, event)

        monkeypatch.setattr(DataTable, "_on_idle", busy)
        draws = 0
        draw = table.render_lines

        def counted(crop: Any) -> Any:
            nonlocal draws
            draws += 1
            return draw(crop)

        monkeypatch.setattr(table, "render_lines", counted)

        def drawn_since(seen: int) -> Callable[[], bool]:
            return lambda: draws > seen

        await type_line(pilot, "watch IO 128-131")
        await until(pilot, lambda: table.row_count == 6, "the new rows")
        for _ in range(3 * REVEAL_TRIES):  # screens drawn before the rows are measured
            table.refresh()
            await until(pilot, drawn_since(draws), "the table drawn again")
        held = False
        table.post_message(events.Idle())
        room = table.scrollable_content_region.height - table.header_height
        await until(
            pilot,
            lambda: round(table.scroll_y) <= 5 < round(table.scroll_y) + room,
            "the new rows in view",
            timeout=5,
        )
