"""The I/O grid's pure logic: grouping, words, per-bit state, layout by width."""

from __future__ import annotations

from dataclasses import replace

import pytest
from rich.cells import cell_len
from rich.style import Style
from rich.text import Text

from rac_console.commands.language import VarRef
from rac_console.engine.published.events import RowView
from rac_console.present.iogrid import (
    NO_DECIMAL,
    STYLE_OFF,
    STYLE_ON,
    Bit,
    BitState,
    Layout,
    bit_style,
    bits_from_rows,
    build_grid,
    cell_text,
    choose_layout,
    fit_label,
    grid_lines,
    word_of,
)
from rac_console.protocol import Variant, kind_of

IO = kind_of("IO")
NOW = 1000.0


def row(
    index: int,
    value: bool | None,
    label: str = "",
    *,
    stale: bool = False,
    changed_at: float | None = NOW - 10,
) -> tuple[VarRef, RowView]:
    var = VarRef(IO, index)
    variant = None if value is None else Variant(IO.vt, value)
    status = "TIMEOUT" if stale else ("OK" if value is not None else "WAITING")
    return var, RowView(var, label, variant, status, stale, changed_at, None)


def rows_of(*pairs: tuple[VarRef, RowView]) -> dict[VarRef, RowView]:
    return dict(pairs)


def bits(on: set[int], indices: range) -> dict[int, Bit]:
    return {i: Bit(i, BitState.ON if i in on else BitState.OFF) for i in indices}


# ------------------------------------------------------------------ grouping


def test_a_range_of_16_aligned_is_one_line() -> None:
    lines = grid_lines(bits({128, 130, 131}, range(128, 144)), 16)
    assert [line.start for line in lines] == [128]
    assert [b.index for b in lines[0].bits] == list(range(128, 144))


def test_lines_of_8_split_a_16_range_in_two() -> None:
    lines = grid_lines(bits(set(), range(128, 144)), 8)
    assert [line.start for line in lines] == [128, 136]


def test_a_range_crossing_an_8_boundary_makes_two_aligned_lines() -> None:
    lines = grid_lines(bits(set(), range(5, 13)), 8)
    assert [line.start for line in lines] == [0, 8]
    first, second = lines
    assert [b.state for b in first.bits[:5]] == [BitState.UNWATCHED] * 5
    assert [b.index for b in first.bits if b.state is not BitState.UNWATCHED] == [5, 6, 7]
    assert [b.index for b in second.bits if b.state is not BitState.UNWATCHED] == [8, 9, 10, 11, 12]
    assert all(b.state is BitState.UNWATCHED for b in second.bits[5:])


def test_the_same_range_in_lines_of_16_is_one_line() -> None:
    lines = grid_lines(bits(set(), range(5, 13)), 16)
    assert [line.start for line in lines] == [0]


def test_sparse_bits_only_make_the_lines_they_fall_in() -> None:
    sparse = {i: Bit(i, BitState.ON) for i in (3, 200, 511)}
    lines = grid_lines(sparse, 16)
    assert [line.start for line in lines] == [0, 192, 496]
    assert sum(b.state is BitState.ON for line in lines for b in line.bits) == 3


def test_only_io_rows_make_bits() -> None:
    p = VarRef(kind_of("P"), 1)
    rows = rows_of(row(1, True))
    rows[p] = RowView(p, "", None, "WAITING", False, None, None)
    assert set(bits_from_rows(rows, NOW)) == {1}


# --------------------------------------------------------------------- words


def test_word_lsb_is_the_lowest_index() -> None:
    line = grid_lines(bits({128, 130, 131}, range(128, 144)), 16)[0]
    assert line.word.value == 0b1101
    assert line.word.hex_text() == "0x000D"
    assert line.word.dec_text() == "13"


@pytest.mark.parametrize(
    ("on", "hex_text", "dec"),
    [
        (set(), "0x0000", "0"),
        (set(range(16)), "0xFFFF", "65535"),
        ({15}, "0x8000", "32768"),
        ({0, 4, 8, 12}, "0x1111", "4369"),
        ({1, 3, 5, 7, 9, 11, 13, 15}, "0xAAAA", "43690"),
    ],
)
def test_word_patterns_16(on: set[int], hex_text: str, dec: str) -> None:
    word = grid_lines(bits(on, range(16)), 16)[0].word
    assert (word.hex_text(), word.dec_text()) == (hex_text, dec)


def test_word_of_8_bits_is_a_byte() -> None:
    word = grid_lines(bits({8, 15}, range(8, 16)), 8)[0].word
    assert (word.hex_text(), word.dec_text()) == ("0x81", "129")


def test_unknown_bits_make_their_hex_digit_a_question_mark_and_no_decimal() -> None:
    # IO 0-7 watched, 8-15 not: the line's number is its low byte, aligned with the rest.
    word = grid_lines(bits({0, 2, 3}, range(8)), 16)[0].word
    assert (word.hex_text(), word.pad) == ("0x0D", 2)  # aligned with 16-bit lines' words
    assert word.dec_text() == "13"
    # One bit without a value yet spoils only its own nibble.
    waiting = bits({0}, range(16)) | {5: Bit(5, BitState.UNKNOWN)}
    word = word_of(tuple(waiting[i] for i in range(16)))
    assert word.hex_text() == "0x00?1"
    assert word.dec_text() == NO_DECIMAL


def test_a_stale_bit_keeps_its_value_and_marks_the_word_stale() -> None:
    rows = rows_of(*(row(i, i == 2, stale=i == 2) for i in range(8)))
    line = grid_lines(bits_from_rows(rows, NOW), 8)[0]
    assert line.word.dec_text() == "4"
    assert line.word.stale
    assert line.bits[2].stale and line.bits[2].state is BitState.ON


# ---------------------------------------------------------------- bit states


def test_states_from_rows() -> None:
    rows = rows_of(
        row(0, True),
        row(1, False),
        row(2, None),
        row(3, None, stale=True, changed_at=None),
        row(4, True, changed_at=NOW - 0.5),
    )
    got = bits_from_rows(rows, NOW)
    assert [got[i].state for i in range(5)] == [
        BitState.ON,
        BitState.OFF,
        BitState.UNKNOWN,
        BitState.UNKNOWN,
        BitState.ON,
    ]
    assert [got[i].changed for i in range(5)] == [False, False, False, False, True]
    assert got[3].stale


def test_cells_show_glyph_index_and_blank_when_unwatched() -> None:
    layout = Layout(8, 3)
    assert cell_text(Bit(128, BitState.ON), layout) == "●128"
    assert cell_text(Bit(129, BitState.OFF), layout) == "○129"
    assert cell_text(Bit(5, BitState.UNKNOWN), layout) == "  ?5"
    assert cell_text(Bit(6, BitState.OFF, stale=True), layout) == "  ○6"
    assert cell_text(Bit(7, BitState.UNWATCHED), layout) == "   ·"


# -------------------------------------------------------------------- labels


def test_labels_are_cut_with_an_ellipsis_to_their_cells() -> None:
    assert fit_label("gripper closed", 6) == "gripp…"
    assert fit_label("ok", 6) == "ok    "
    assert cell_len(fit_label("グリッパー閉", 7)) == 7  # wide characters count 2 cells
    assert fit_label("a\x1b[2Jb", 12) == "a\\x1b[2Jb   "  # escaped, never obeyed


def test_labels_show_only_where_the_width_allows() -> None:
    indices = range(128, 144)
    assert choose_layout(78, indices, ["gripper"]).label_width == 0
    wide = choose_layout(240, indices, ["gripper"])
    assert (wide.per_line, wide.label_width) == (16, 7)
    assert choose_layout(240, indices, ["x" * 40]).label_width <= 16


def test_a_labelled_grid_fits_its_width() -> None:
    rows = rows_of(*(row(i, i % 3 == 0, "gripper closed" if i == 130 else "") for i in range(64)))
    for width in (42, 60, 78, 100, 120, 198, 240):
        grid = build_grid(rows, NOW, width)
        assert max(len(line) for line in grid.text.plain.split("\n")) <= max(width, 42)


# -------------------------------------------------------------------- layout


@pytest.mark.parametrize(
    ("width", "per_line"),
    [(40, 8), (60, 8), (75, 8), (76, 16), (118, 16), (198, 16)],
)
def test_16_bits_a_line_when_the_width_allows_else_8(width: int, per_line: int) -> None:
    assert choose_layout(width, range(64)).per_line == per_line


def test_80_columns_show_64_bits_in_4_lines() -> None:
    rows = rows_of(*(row(i, i in (0, 2, 3)) for i in range(64)))
    grid = build_grid(rows, NOW, 78)  # an 80-column panel inside its border
    lines = grid.text.plain.split("\n")
    assert len(lines) == 4
    assert lines[0] == (
        "  0   1   2   3   4   5   6   7    8   9  10  11  12  13  14  15  0x000D    13"
    )


def cells_of(line: Text, layout: Layout) -> list[tuple[str, str]]:
    """The (text, style) of each cell of a rendered line, read back from its spans."""
    return [
        (line.plain[span.start : span.end], str(span.style))
        for span in line.spans[: layout.per_line]
    ]


def test_at_80_columns_io_128_to_191_make_4_lines_of_separated_cells() -> None:
    """The issue: ``●128○129●130●131○132…`` ran together at 80 columns."""
    rows = rows_of(*(row(i, i in (128, 130, 131)) for i in range(128, 192)))
    grid = build_grid(rows, NOW, 78)
    lines = grid.text.split("\n")
    assert len(lines) == 4 and grid.layout.per_line == 16
    assert all(len(line.plain) <= 78 for line in lines)
    cells = cells_of(lines[0], grid.layout)
    assert [text for text, _ in cells] == [str(i) for i in range(128, 144)]
    # Every two cells have an unstyled blank between them: never `128129`.
    for first, second in zip(lines[0].spans[:15], lines[0].spans[1:16], strict=True):
        between = lines[0].plain[first.end : second.start]
        assert between.strip() == "" and len(between) >= 1
    assert "128 129 130 131" in lines[0].plain
    assert [style for _, style in cells[:4]] == [STYLE_ON, STYLE_OFF, STYLE_ON, STYLE_ON]


def test_the_symbol_stays_where_there_is_room() -> None:
    rows = rows_of(*(row(i, i == 128) for i in range(128, 144)))
    wide = build_grid(rows, NOW, 118)
    assert wide.layout.glyph
    assert wide.text.plain.startswith("●128 ○129 ○130")
    assert not build_grid(rows, NOW, 78).layout.glyph


@pytest.mark.parametrize("width", [40, 60, 78, 100, 118, 160, 240])
@pytest.mark.parametrize("indices", [range(0, 64), range(128, 192), range(1000, 1064)])
def test_cells_are_always_separated(width: int, indices: range) -> None:
    layout = choose_layout(width, indices)
    assert layout.sep == 1
    rows = rows_of(*(row(i, i % 2 == 0) for i in indices))
    grid = build_grid(rows, NOW, width)
    for line in grid.text.split("\n"):
        for first, second in zip(line.spans, line.spans[1 : layout.per_line], strict=False):
            assert line.plain[first.end : second.start].isspace()


def test_four_digit_indices_at_80_columns_keep_a_blank_and_the_symbol() -> None:
    layout = choose_layout(78, range(1000, 1064))
    assert (layout.per_line, layout.sep, layout.glyph) == (8, 1, True)


def test_without_the_symbol_every_mark_is_its_own_style() -> None:
    """ON, OFF, no value, stale ON/OFF, changed ON/OFF, unwatched, cursor ON/OFF and a
    write in flight: each drawn differently when the cell is only digits."""
    styles = {
        "on": bit_style(Bit(1, BitState.ON)),
        "off": bit_style(Bit(1, BitState.OFF)),
        "no value": bit_style(Bit(1, BitState.UNKNOWN)),
        "stale on": bit_style(Bit(1, BitState.ON, stale=True)),
        "stale off": bit_style(Bit(1, BitState.OFF, stale=True)),
        "changed on": bit_style(Bit(1, BitState.ON, changed=True)),
        "changed off": bit_style(Bit(1, BitState.OFF, changed=True)),
        "cursor on": bit_style(Bit(1, BitState.ON), cursor=True),
        "cursor off": bit_style(Bit(1, BitState.OFF), cursor=True),
        "in flight on": bit_style(Bit(1, BitState.ON), pending=True),
        "in flight off": bit_style(Bit(1, BitState.OFF), pending=True),
    }
    parsed = {name: Style.parse(style) for name, style in styles.items()}
    assert len(set(parsed.values())) == len(parsed)
    assert parsed["on"].reverse and parsed["on"].bold
    assert parsed["off"].dim
    assert parsed["no value"].strike
    assert parsed["stale on"].italic and parsed["stale off"].italic
    assert parsed["in flight on"].underline and parsed["in flight off"].underline
    # The unwatched cell is a `·`, never digits: told apart by its text.
    assert cell_text(Bit(7, BitState.UNWATCHED), Layout(16, 3, glyph=False)) == "  ·"


def test_four_digit_indices_widen_every_cell() -> None:
    layout = choose_layout(200, [1000, 1001])
    assert layout.index_width == 4
    assert cell_text(Bit(1000, BitState.ON), layout) == "●1000"
    assert cell_text(Bit(1000, BitState.ON), replace(layout, glyph=False)) == "1000"
    assert cell_text(Bit(5, BitState.UNKNOWN), replace(layout, glyph=False)) == "   5"


def test_the_grid_knows_each_bit() -> None:
    grid = build_grid(rows_of(row(130, True)), NOW, 100)
    bit = grid.bit(130)
    assert bit is not None and bit.state is BitState.ON
    assert grid.bit(131) == Bit(131, BitState.UNWATCHED)
    assert grid.bit(500) is None
