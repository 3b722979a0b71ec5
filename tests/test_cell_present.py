"""A cell's presentation, without a screen: the badges, the filter by target, the
completion of ``use NAME`` and ``@NAME``, the table's order grouped by target."""

from __future__ import annotations

import time
from dataclasses import replace

from rac_console.commands.language import parse_var
from rac_console.engine.published.events import RowView, Status
from rac_console.present.cell_status import Badge, cell_status_text
from rac_console.present.completion import complete
from rac_console.present.filtering import FrameFilter
from rac_console.present.table_rows import SortMode, ordered_keys, table_key
from rac_console.protocol import parse_request

STATUS = Status(
    target="LIVE 10.0.0.1:5006",
    is_simulator=False,
    has_session=True,
    host="10.0.0.1",
    port=5006,
    timeout=2.0,
    read_only=False,
    connection="connected",
    retry_at=None,
    rtt=0.0042,
    paused=False,
    watched=3,
    interval=0.2,
    period=0.2,
    cycle_seconds=None,
    polls_per_second=None,
    interval_met=True,
    record_failure=None,
    seen=frozenset(),
)
CELL = [("robotA", "Cell A"), ("robotB", "Cell B"), ("welding-cell-3", "Cell 3")]


def test_three_badges_fit_80_columns_whatever_their_state() -> None:
    now = time.monotonic()
    badges = [
        Badge("robotA", replace(STATUS, writes="read-only"), "green", current=True),
        Badge("robotB", replace(STATUS, connection="refused", retry_at=now + 3.5), "magenta"),
        Badge("welding-cell-3", replace(STATUS, writes="confirm"), "#ff8700"),
    ]
    line = cell_status_text(badges, 80, now)
    assert line.cell_len <= 80, line.plain
    plain = line.plain
    assert "robotA" in plain and "robotB" in plain and "weldi" in plain
    assert "RO" in plain and "ask" in plain  # read-only and confirm, abbreviated
    assert "refused 4s" in plain  # the backoff's countdown: one target down, said so
    wide = cell_status_text(badges, 200, now).plain
    assert "read-only" in wide and "confirm" in wide and "retry 3.5s" in wide
    assert "welding-cell-3" in wide


def test_a_badge_escapes_a_name_from_the_config() -> None:
    line = cell_status_text([Badge("evil\x1b[2J", STATUS)], 80).plain
    assert "\x1b" not in line


def test_the_frame_filter_names_a_target() -> None:
    get = parse_request(b"GET:RC8:64:IO:\r")
    only_b = FrameFilter.of("@robotB")
    assert only_b and only_b.target == "robotB"
    assert only_b.matches(get, "→ GET:RC8:64:IO:↵", "robotB")
    assert not only_b.matches(get, "→ GET:RC8:64:IO:↵", "robotA")
    assert not only_b.matches(get, "→ GET:RC8:64:IO:↵")  # a frame of no target
    both = FrameFilter.of("/robotB IO64")  # the slash form, and a variable after it
    assert both.target == "robotB" and both.var == ("IO", 64)
    assert both.matches(get, "", "robotB")
    assert not both.matches(parse_request(b"GET:RC8:65:IO:\r"), "", "robotB")
    assert FrameFilter.of("IO64").target is None  # as before, outside a cell


def test_completion_offers_at_name_and_use_name() -> None:
    names = [c.text for c in complete("@rob", cell=CELL)]
    assert names == ["@robotA", "@robotB"]
    assert [c.text for c in complete("@robotA get I", cell=CELL)] == ["I", "IO"]
    used = [c.text for c in complete("use ", cell=CELL)]
    assert used == ["robotA", "robotB", "welding-cell-3"]
    assert complete("@rob") == []  # no cell: nothing to offer


def _row(text: str, changed: float | None = None) -> RowView:
    var, _ = parse_var(text, "")
    return RowView(var, "", None, "OK", False, changed, None)


def test_a_cell_table_groups_rows_by_target_in_cell_order() -> None:
    rows = [
        ("robotB", _row("I 10", 5.0)),
        ("robotA", _row("IO 128", 1.0)),
        ("robotA", _row("I 10", 9.0)),
    ]
    views = {table_key(name, row.var, True): row for name, row in rows}
    added = {key: n for n, key in enumerate(views)}
    groups = {table_key(n, r.var, True): ({"robotA": 0, "robotB": 1}[n], n) for n, r in rows}
    assert ordered_keys(views, added, SortMode.ADDED, groups=groups) == [
        "robotA IO128",
        "robotA I10",
        "robotB I10",
    ]
    assert ordered_keys(views, added, SortMode.CHANGED, groups=groups)[:2] == [
        "robotA I10",
        "robotA IO128",
    ]
    # The filter matches a target's name too.
    assert ordered_keys(views, added, SortMode.ADDED, "robotb", groups=groups) == ["robotB I10"]


def test_a_running_line_says_how_to_cancel_after_the_badges() -> None:
    badges = [Badge("robotA", STATUS, "green", current=True), Badge("robotB", STATUS)]
    line = cell_status_text(badges, 120, running=("wait IO 128 on", 3.2, 1)).plain
    assert line.index("robotB") < line.index("Esc cancels: wait IO 128 on (3 s) +1")
    assert "Esc" not in cell_status_text(badges, 120, running=("get I 1", 0.1, 0)).plain


def test_the_log_escapes_a_target_name_from_the_config() -> None:
    from rac_console.session import Frame
    from rac_console.tui.frame_log import FrameLog

    log = FrameLog()
    log.target_width = 8
    frame = Frame(1_700_000_000.0, "tx", b"GET:RC8:1:I:\r", None)
    log.add(frame, "bad\x1b[2J")
    line, _ = log._frame_line(frame, None)
    assert "\x1b" not in line and "GET:RC8:1:I:" in line
