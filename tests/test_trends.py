"""The trend store, sparkline text, table row order and the row keys' put lines (pure)."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from rac_console.commands.exchange_parsers import parse_put
from rac_console.commands.language import VarRef
from rac_console.commands.outcome import ExitStatus, Outcome
from rac_console.engine.published.events import Cycle, Message, Result, RowView
from rac_console.present.row_actions import put_line, toggle_line
from rac_console.present.table_rows import SortMode, visible_keys
from rac_console.present.toggles import PendingToggles
from rac_console.present.trends import (
    GAP,
    TrendStore,
    bar_lines,
    bin_window,
    field_value,
    number_text,
    span_text,
    sparkline_text,
)
from rac_console.protocol import Variant, kind_of
from rac_console.protocol.vartypes import VT, VT_ARRAY

I0 = VarRef(kind_of("I"), 0)
F0 = VarRef(kind_of("F"), 0)
P1 = VarRef(kind_of("P"), 1)
S1 = VarRef(kind_of("S"), 1)
IO130 = VarRef(kind_of("IO"), 130)


def cycle(t: float, *samples: tuple[VarRef, Variant | None]) -> Cycle:
    return Cycle(1_700_000_000 + t, t, samples)


def i4(value: int) -> Variant:
    return Variant(VT.I4, value)


def pos(*values: float) -> Variant:
    return Variant(VT.R4 | VT_ARRAY, list(values))


# ------------------------------------------------------------------ the store


def test_store_keeps_the_newest_samples_per_variable_only() -> None:
    store = TrendStore(raw=8, step=1.0, horizon=4.0)
    for t in range(100):
        store.add_cycle(cycle(t * 0.1, (I0, i4(t))))
    assert store.last(I0, 0, 100) == [float(t) for t in range(92, 100)]
    assert store.last(I0, 0, 3) == [97.0, 98.0, 99.0]
    assert len(store._series[I0].coarse) == 4  # one per second, 4 s reach


def test_a_string_row_gets_no_series_and_unknown_rows_read_empty() -> None:
    store = TrendStore()
    store.add_cycle(cycle(1.0, (S1, Variant(VT.BSTR, "x")), (I0, i4(1))))
    assert S1 not in store and I0 in store
    assert store.last(S1, 0, 5) == []
    assert store.window(F0, 0, 10).count == 0


def test_window_min_max_last_over_the_last_seconds() -> None:
    store = TrendStore()
    for t, value in enumerate([5, 1, 9, 3, 4, 7]):
        store.add_cycle(cycle(float(t), (I0, i4(value))))
    window = store.window(I0, 0, 3.0)  # t = 2..5: 9 3 4 7
    assert window.values == [9.0, 3.0, 4.0, 7.0]
    assert (window.low, window.high, window.last, window.count) == (3.0, 9.0, 7.0, 4)
    assert not window.thinned
    everything = store.window(I0, 0, 60.0)
    assert (everything.low, everything.high, everything.count) == (1.0, 9.0, 6)


def test_window_with_failed_polls_keeps_the_gaps_and_the_last_good_value() -> None:
    store = TrendStore()
    store.add_cycle(cycle(0.0, (I0, i4(4))))
    store.add_cycle(cycle(1.0, (I0, None)))
    window = store.window(I0, 0, 10)
    assert window.values == [4.0, None]
    assert (window.last, window.failed) == (4.0, 1)


def test_a_window_longer_than_the_raw_samples_reads_the_thinned_record() -> None:
    store = TrendStore(raw=10, step=1.0, horizon=100.0)
    for n in range(200):  # 10 samples a second for 20 s
        store.add_cycle(cycle(n / 10, (I0, i4(n))))
    short = store.window(I0, 0, 0.45)
    assert not short.thinned and short.values == [195.0, 196.0, 197.0, 198.0, 199.0]
    long = store.window(I0, 0, 30.0)
    assert long.thinned
    assert long.values[:3] == [0.0, 10.0, 20.0]  # one a second, then every raw one
    assert long.values[-10:] == [float(n) for n in range(190, 200)]
    assert (long.low, long.high) == (0.0, 199.0)


def test_fields_are_split_when_read() -> None:
    store = TrendStore()
    store.add_cycle(cycle(0.0, (P1, pos(1, 2, 3, 0, 0, 0, 5))))
    store.add_cycle(cycle(1.0, (P1, pos(1, 2, 4, 0, 0, 0, 5))))
    assert store.last(P1, 2, 5) == [3.0, 4.0]  # Z
    assert store.last(P1, 6, 5) == [5.0, 5.0]  # Fig
    assert store._series[P1].raw[0][1] == [1, 2, 3, 0, 0, 0, 5]  # stored whole


def test_field_values() -> None:
    assert field_value(True, 0) == 1.0 and field_value(False, 0) == 0.0
    assert field_value([1.5, 2.5], 1) == 2.5
    assert field_value([1.5], 3) is None
    assert field_value(None, 0) is None
    assert field_value("abc", 0) is None
    assert field_value(math.nan, 0) is None


def test_forget_drops_a_series() -> None:
    store = TrendStore()
    store.add_cycle(cycle(0.0, (I0, i4(1))))
    store.forget(I0)
    assert I0 not in store


# ------------------------------------------------------------------ sparklines


def test_sparkline_scales_min_to_max_and_right_aligns() -> None:
    assert sparkline_text([0, 7, 3.5], 5) == "  ▁█▅"  # 3.5 of 7 rounds up to ▅
    assert sparkline_text(list(range(8)), 8) == "▁▂▃▄▅▆▇█"
    assert sparkline_text(list(range(20)), 4) == "▁▃▆█"  # only the newest 4


def test_sparkline_flat_series_sits_mid_height() -> None:
    assert sparkline_text([3, 3, 3], 3) == "▄▄▄"


def test_sparkline_one_sample_and_none() -> None:
    assert sparkline_text([2.0], 4) == "   ▄"
    assert sparkline_text([], 4) == "    "
    assert sparkline_text([None, None], 3) == f" {GAP}{GAP}"


def test_sparkline_gaps_and_a_fixed_scale() -> None:
    assert sparkline_text([0, None, 1], 3, 0.0, 1.0) == f"▁{GAP}█"
    assert sparkline_text([1, 1, 1], 3, 0.0, 1.0) == "███"  # IO: all ON stays on top
    assert sparkline_text([5], 0) == ""


# ------------------------------------------------------------ binning by time


def fed(seconds: float, every: float, value, var: VarRef = I0, start: float = 0.0) -> TrendStore:
    """A store with a sample every ``every`` s for ``seconds`` s; ``value(t)`` gives each."""
    store = TrendStore()
    for n in range(round(seconds / every) + 1):
        t = start + n * every
        store.add_cycle(
            cycle(t, (var, Variant(VT.BOOL, value(t)) if var is IO130 else i4(value(t))))
        )
    return store


@pytest.mark.parametrize("width", [20, 37, 76, 80])
def test_93_s_of_data_in_a_5_min_window_fill_only_the_last_slices(width: int) -> None:
    """The issue: 93 s of samples were stretched over the whole 5 min sparkline."""
    store = fed(93.0, 0.2, lambda t: int(t) % 7)
    window = store.window(I0, 0, 300.0)
    bins = bin_window(window, width)
    assert len(bins) == width
    filled = [n for n, b in enumerate(bins) if b is not None]
    assert filled == list(range(width - math.ceil(93 / 300 * width), width))
    assert window.covered == pytest.approx(93.0)
    lines = bar_lines(bins, 3, window.low, window.high)
    empty = width - len(filled)
    assert all(line[:empty] == " " * empty for line in lines)  # no data: blank


def test_a_full_window_covers_its_seconds_and_a_slice_is_a_fixed_time() -> None:
    store = fed(20.0, 0.5, lambda t: t)
    window = store.window(I0, 0, 10.0)
    assert window.covered == 10.0  # there are samples before it: it is all data
    bins = bin_window(window, 10)  # 1 s a slice
    assert all(b is not None for b in bins)
    assert [b.high for b in bins if b is not None] == [10.5 + n for n in range(9)] + [20.0]
    assert bins[0] is not None and bins[0].low == 10.0


def test_a_bit_toggling_faster_than_a_slice_shows_both_levels() -> None:
    """IO toggling every 0.2 s, polled every 0.1 s, 10 s in a 10 s window 20 wide: each
    slice (0.5 s) was both ON and OFF, so each column spans bottom to top; a steady ON
    is a block at the top only and a steady OFF a line at the bottom (as a logic
    analyser draws a signal)."""
    toggling = fed(10.0, 0.1, lambda t: int(t / 0.2 + 1e-9) % 2 == 1, var=IO130)
    window = toggling.window(IO130, 0, 10.0)
    bins = bin_window(window, 20)
    assert all(b is not None and (b.low, b.high) == (0.0, 1.0) for b in bins)
    assert all(b is not None and 0.3 < b.mean < 0.7 for b in bins)  # type: ignore[operator]
    assert bar_lines(bins, 3, 0.0, 1.0) == ["█" * 20] * 3
    steady_on = bin_window(fed(10.0, 0.1, lambda t: True, var=IO130).window(IO130, 0, 10.0), 20)
    assert bar_lines(steady_on, 3, 0.0, 1.0) == ["█" * 20, " " * 20, " " * 20]
    steady_off = bin_window(fed(10.0, 0.1, lambda t: False, var=IO130).window(IO130, 0, 10.0), 20)
    assert bar_lines(steady_off, 3, 0.0, 1.0) == [" " * 20, " " * 20, "▁" * 20]
    # One line has no room for a range: there a column is the slice's mean (duty cycle).
    assert set(bar_lines(bins, 1, 0.0, 1.0)[0]) <= set("▃▄▅▆")
    assert bar_lines(steady_on, 1, 0.0, 1.0) == ["█" * 20]


def test_a_short_on_inside_a_slice_still_shows() -> None:
    store = fed(10.0, 0.1, lambda t: 4.0 <= t < 4.15, var=IO130)  # ON for 2 polls
    bins = bin_window(store.window(IO130, 0, 10.0), 10)
    lines = bar_lines(bins, 2, 0.0, 1.0)
    assert lines[0][4] == "█" and lines[1][4] == "█"
    assert lines[0].count("█") == 1


def test_slices_with_only_failed_polls_are_gaps() -> None:
    store = TrendStore()
    store.add_cycle(cycle(0.0, (I0, i4(1))))
    store.add_cycle(cycle(5.0, (I0, None)))
    store.add_cycle(cycle(9.9, (I0, i4(3))))
    bins = bin_window(store.window(I0, 0, 10.0), 10)
    assert bins[5] is not None and bins[5].high is None and bins[5].failed == 1
    lines = bar_lines(bins, 2, 1.0, 3.0)
    assert lines[-1][5] == GAP
    assert [line[1] for line in lines] == [" ", "▁"]  # 1 held until the next poll
    assert [line[6] for line in lines] == [" ", " "]  # after a failed poll: unknown


def test_slices_between_polls_hold_the_last_value() -> None:
    """Polls every 0.5 s, slices of 0.13 s: a slice with no poll shows the value polled
    before it (also from before the window), not a hole."""
    store = fed(20.0, 0.5, lambda t: 5 if t < 15 else 9)
    bins = bin_window(store.window(I0, 0, 10.0), 77)
    assert all(b is not None for b in bins)
    assert bins[0] is not None and bins[0].high == 5.0  # held from before the window
    assert bins[-1] is not None and bins[-1].high == 9.0


def test_span_text() -> None:
    assert span_text(93.0000001) == "93 s"
    assert span_text(4.25) == "4.2 s"
    assert span_text(150) == "2 min 30 s"
    assert span_text(120) == "2 min"


def test_number_text() -> None:
    assert number_text(None) == "—"
    assert number_text(42.0) == "42"
    assert number_text(36.51234567) == "36.5123"


# ------------------------------------------------------------------ table order


def row(var: VarRef, label: str = "", changed_at: float | None = None) -> RowView:
    return RowView(var, label, None, "OK", False, changed_at, None)


ROWS = [row(P1, "pick", 3.0), row(IO130, "gripper", 5.0), row(I0, "", None), row(F0, "Temp", 1.0)]
ADDED = {r.key: n for n, r in enumerate(ROWS)}


def test_sort_modes() -> None:
    assert visible_keys(ROWS, ADDED, SortMode.ADDED) == ["P1", "IO130", "I0", "F0"]
    assert visible_keys(ROWS, ADDED, SortMode.NAME) == ["F0", "I0", "IO130", "P1"]
    assert visible_keys(ROWS, ADDED, SortMode.CHANGED) == ["IO130", "P1", "F0", "I0"]
    assert SortMode.ADDED.next() is SortMode.NAME
    assert SortMode.CHANGED.next() is SortMode.ADDED


def test_filter_by_name_or_label_any_case_and_hidden_io() -> None:
    assert visible_keys(ROWS, ADDED, SortMode.ADDED, "temp") == ["F0"]
    assert visible_keys(ROWS, ADDED, SortMode.ADDED, "i") == ["P1", "IO130", "I0"]
    assert visible_keys(ROWS, ADDED, SortMode.ADDED, "", hide_io=True) == ["P1", "I0", "F0"]
    assert visible_keys(ROWS, ADDED, SortMode.ADDED, "grip", hide_io=True) == []


# ------------------------------------------------------------------ put lines


@pytest.mark.parametrize(
    ("var", "variant", "line"),
    [
        (P1, pos(350, 0, 450, 180, 0, 180, 5), "put P 1 350 0 450 180 0 180 5"),
        (P1, pos(0.1, -2.5, 1e-05, 0, 0, 0, -1), "put P 1 0.1 -2.5 1e-05 0 0 0 -1"),
        (IO130, Variant(VT.BOOL, True), "put IO 130 on"),
        (IO130, Variant(VT.BOOL, False), "put IO 130 off"),
        (I0, i4(-12), "put I 0 -12"),
        (F0, Variant(VT.R4, 36.5), "put F 0 36.5"),
        (VarRef(kind_of("D"), 2), Variant(VT.R8, 0.1 + 0.2), "put D 2 0.30000000000000004"),
        (S1, Variant(VT.BSTR, "a b "), 'put S 1 "a b "'),
        (S1, Variant(VT.BSTR, ""), 'put S 1 ""'),
        (S1, Variant(VT.BSTR, 'say "hi"'), "put S 1 'say \"hi\"'"),
        (S1, Variant(VT.BSTR, 'it\'s "x"'), 'put S 1 it\'s "x"'),
    ],
)
def test_put_line_round_trips(var: VarRef, variant: Variant, line: str) -> None:
    made = put_line(var, variant)
    assert made == replace(made, text=line, problem=None)
    assert parse_put(line[4:]).value.value == variant.value


def test_put_line_without_a_value_or_with_one_that_cannot_be_typed() -> None:
    assert put_line(P1, None).text == "put P 1 " and put_line(P1, None).problem is None
    for variant in (Variant(VT.BSTR, "bell\x07"), Variant(VT.BSTR, '"it\'s"')):
        made = put_line(S1, variant)
        assert made.text == "put S 1 " and made.problem
    assert put_line(P1, pos(math.inf, 0, 0, 0, 0, 0, 0)).text == "put P 1 "


def test_toggle_line() -> None:
    assert toggle_line(IO130, Variant(VT.BOOL, True)) == "put IO 130 off"
    assert toggle_line(IO130, Variant(VT.BOOL, False)) == "put IO 130 on"
    assert toggle_line(IO130, None) is None
    assert toggle_line(I0, i4(1)) is None


def ok(seq: int) -> Result:
    outcome = Outcome("PUT:RC8:130:IO:11,0", ExitStatus.OK, IO130, written=Variant(VT.BOOL, False))
    return Result(seq, (outcome,), "put IO 130 off")


def test_a_toggle_is_busy_until_a_poll_shows_the_value_written() -> None:
    toggles = PendingToggles()
    toggles.start(IO130, seq=7, value=False)
    assert toggles.busy(IO130)
    assert not toggles.cycle(cycle(0.0, (IO130, Variant(VT.BOOL, False))))  # before the reply
    assert not toggles.result(ok(7))
    assert toggles.busy(IO130)
    assert toggles.cycle(cycle(1.0, (IO130, Variant(VT.BOOL, False))))
    assert not toggles.busy(IO130)


def test_a_toggle_polled_before_the_write_waits_for_a_second_cycle() -> None:
    toggles = PendingToggles()
    toggles.start(IO130, seq=7, value=False)
    toggles.result(ok(7))
    assert not toggles.cycle(cycle(1.0, (IO130, Variant(VT.BOOL, True))))  # polled before it
    assert toggles.cycle(cycle(2.0, (IO130, Variant(VT.BOOL, True))))  # driven back: free


def test_a_refused_toggle_is_free_at_once() -> None:
    toggles = PendingToggles()
    toggles.start(IO130, seq=3, value=False)
    assert not toggles.result(Result(2, (Message("other"),)))
    assert toggles.result(Result(3, (Message("PUT refused: read-only", "error"),)))
    assert not toggles.busy(IO130)


def test_a_toggle_answered_no_frees_its_row_at_once() -> None:
    """No write went out: the next Space on the row must not wait for the refusal."""
    toggles = PendingToggles()
    toggles.start(IO130, 7, False)
    toggles.start(I0, 8, True)
    toggles.declined(7)
    assert not toggles.busy(IO130)
    assert toggles.busy(I0)  # another row's write still on its way
