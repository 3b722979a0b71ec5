"""The I/O grid: watched IO bits as lines of 8 or 16 with each line's word.

Pure (rich only for the finished text), so grouping, words and layout are tested
without a screen. A line starts at a multiple of its width (IO 128-143 is one line of
16) and its word is read the way DENSO reads IOW/IOB words: **the lowest index of the
line is bit 0 (the LSB)**, so IO 128, 130 and 131 ON in line 128-143 make 0x000D = 13.

A bit with no value (not watched, not polled yet, or failed before any value) makes
its hex digit ``?`` and the decimal ``—``: a word is never shown with guessed bits.
A stale bit keeps its last value, as the table does, and marks the word stale.

Cells are always apart: a blank between every two cells (and one more between the
bytes of a 16-bit line where it fits). Each cell is its index, right-aligned, drawn in
the style of its state; the ``●``/``○`` symbol before the digits is an extra, shown only
where it fits (at 80 columns 16 cells of 3-digit indices fit only without it). So the
state is always read from the style alone:

====================  ===================================================  =============
state                 style                                                text
====================  ===================================================  =============
ON                    bold reverse green (a green block)                   ``●130``
OFF                   dim                                                  ``○130``
no value yet          struck through                                       ``?130``
stale ON / OFF        italic on dark green / dim italic (value kept)       as ON / OFF
changed (1 s)         the table's highlight: olive background, ON's
                      digits green on it (light themes: pale amber, ON     as ON / OFF
                      dark green, OFF grey; see ``cells.ChangeStyle``)
not watched           dim                                                  ``·``
cursor                blue background, ON's digits bold green, OFF's plain as ON / OFF
write in flight       underlined, over any of the above                    as ON / OFF
====================  ===================================================  =============

The cursor's bit, its state and its label are also said in the panel's bottom border.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from enum import Enum

from rich.cells import cell_len, set_cell_size
from rich.text import Text

from ..commands.language import VarRef
from ..engine.published.events import RowView
from ..protocol.text import terminal_safe
from .table_cells import CHANGED_DARK, HIGHLIGHT_SECONDS, ChangeStyle

GLYPH_ON = "●"
GLYPH_OFF = "○"
GLYPH_UNKNOWN = "?"
GLYPH_UNWATCHED = "·"
NO_DECIMAL = "—"

#: A label cut shorter than this says nothing: below it, no labels are shown.
MIN_LABEL = 4
MAX_LABEL = 16

#: Each state has its own style, so a cell reads without its symbol (see the table above).
STYLE_ON = "bold reverse green"
STYLE_OFF = "dim"
STYLE_UNKNOWN = "strike"
STYLE_STALE = "dim italic"  # the word's, and a stale OFF bit's
STYLE_STALE_ON = "italic on dark_green"
STYLE_CHANGED_ON = CHANGED_DARK.bit_on  # a dark theme's; a light one has its own
STYLE_UNWATCHED = "dim"
STYLE_HEX = "bold cyan"
STYLE_CURSOR = "on blue"
STYLE_CURSOR_ON = "bold bright_green"
STYLE_PENDING = "underline"


class BitState(Enum):
    UNWATCHED = "unwatched"
    UNKNOWN = "unknown"  # watched, no value yet
    ON = "on"
    OFF = "off"


@dataclass(frozen=True, slots=True)
class Bit:
    index: int
    state: BitState
    label: str = ""
    stale: bool = False
    changed: bool = False

    @property
    def has_value(self) -> bool:
        return self.state in (BitState.ON, BitState.OFF)


@dataclass(frozen=True, slots=True)
class Word:
    """A line's bits as a number: bit n is the line's n-th index (the LSB its lowest)."""

    value: int  # the bits that have one; unknown bits are 0 here
    known: int  # mask of the bits that have a value
    width: int  # 8 or 16
    stale: bool = False
    changed: bool = False
    span: int = 0  # the bits the number is made of: 8 when a line's high byte is unwatched

    @property
    def bits(self) -> int:
        return self.span or self.width

    @property
    def complete(self) -> bool:
        return self.known == (1 << self.bits) - 1

    @property
    def pad(self) -> int:
        """Blanks before the hex, so that a byte's lines up with a line's 16 bits."""
        return (self.width - self.bits) // 4

    def hex_text(self) -> str:
        """``0x000D``; a hex digit with any unknown bit is ``?`` (``0x00?1``); a 16-bit
        line watched in its low byte only is that byte (``0x0D``: IO 0-7 watched is no
        number with unknown digits; drawn after :attr:`pad` blanks, aligned)."""
        digits = ["0x"]
        for nibble in reversed(range(self.bits // 4)):
            shift = nibble * 4
            if (self.known >> shift) & 0xF == 0xF:
                digits.append(f"{(self.value >> shift) & 0xF:X}")
            else:
                digits.append("?")
        return "".join(digits)

    def dec_text(self) -> str:
        return str(self.value) if self.complete else NO_DECIMAL


@dataclass(frozen=True, slots=True)
class GridLine:
    start: int
    bits: tuple[Bit, ...]
    word: Word


@dataclass(frozen=True, slots=True)
class Layout:
    """How the lines are drawn in a given width; chosen by :func:`choose_layout`."""

    per_line: int  # 8 or 16
    index_width: int
    sep: int = 0  # spaces between cells
    label_width: int = 0  # 0: no labels
    byte_gap: int = 0  # an extra space between the two bytes of a 16-bit line
    word_gap: int = 1  # spaces before the word
    glyph: bool = True  # the ●/○ symbol before the digits (the style shows the state anyway)

    @property
    def cell_width(self) -> int:
        label = 1 + self.label_width if self.label_width else 0
        return self.glyph + self.index_width + label

    @property
    def word_width(self) -> int:
        """`` 0x000D 65535``: the gap, the hex, a space, the decimal right-aligned."""
        return self.word_gap + 2 + self.per_line // 4 + 1 + len(str((1 << self.per_line) - 1))

    @property
    def width(self) -> int:
        cells = self.per_line * self.cell_width + (self.per_line - 1) * self.sep
        return cells + self.byte_gap + self.word_width


def bits_from_rows(rows: Mapping[VarRef, RowView], now: float) -> dict[int, Bit]:
    """The watched IO bits by index, each with its state (other kinds are left out)."""
    bits: dict[int, Bit] = {}
    for var, row in rows.items():
        if var.kind.code != "IO":
            continue
        variant = row.variant
        if variant is None:
            state = BitState.UNKNOWN
        else:
            state = BitState.ON if bool(variant.value) else BitState.OFF
        changed = (
            not row.stale
            and row.changed_at is not None
            and now - row.changed_at < HIGHLIGHT_SECONDS
        )
        bits[var.index] = Bit(var.index, state, row.label, row.stale, changed)
    return bits


def grid_lines(bits: Mapping[int, Bit], per_line: int) -> list[GridLine]:
    """Lines of ``per_line`` bits, each starting at a multiple of it, for every block
    holding a watched bit; the unwatched bits of such a line are filled in."""
    starts = sorted({index - index % per_line for index in bits})
    lines = []
    for start in starts:
        line = tuple(
            bits.get(index, Bit(index, BitState.UNWATCHED))
            for index in range(start, start + per_line)
        )
        lines.append(GridLine(start, line, word_of(line)))
    return lines


def word_of(bits: tuple[Bit, ...]) -> Word:
    """The word of one line: ``bits[0]`` (the lowest index) is bit 0."""
    value = known = 0
    for n, bit in enumerate(bits):
        if bit.has_value:
            known |= 1 << n
            if bit.state is BitState.ON:
                value |= 1 << n
    byte = len(bits) == 16 and all(bit.state is BitState.UNWATCHED for bit in bits[8:])
    return Word(
        value,
        known,
        len(bits),
        stale=any(bit.stale for bit in bits),
        changed=any(bit.changed for bit in bits),
        span=8 if byte else 0,
    )


def choose_layout(width: int, indices: Iterable[int], labels: Iterable[str] = ()) -> Layout:
    """16 bits a line when 16 cells of bare digits, a blank apart, fit in ``width``
    columns, else 8; then the widest of: a gap between the bytes, the ``●``/``○`` symbol,
    labels, each only where the width allows. Cells are never drawn touching."""
    index_width = max((len(str(i)) for i in indices), default=3)
    index_width = max(index_width, 3)
    per_line = 16 if Layout(16, index_width, sep=1, glyph=False).width <= width else 8
    layout = Layout(per_line, index_width, sep=1, glyph=False)
    byte_gap = 1 if per_line == 16 else 0
    for step in (  # each wider than the last
        Layout(per_line, index_width, sep=1, word_gap=2, glyph=False),
        Layout(per_line, index_width, sep=1, byte_gap=byte_gap, word_gap=2, glyph=False),
        Layout(per_line, index_width, sep=1, word_gap=2),
        Layout(per_line, index_width, sep=1, byte_gap=byte_gap, word_gap=2),
    ):
        if step.width <= width:
            layout = step
    longest = min(max((cell_len(terminal_safe(label)) for label in labels), default=0), MAX_LABEL)
    if longest:
        spare = (width - layout.width) // per_line - 1  # a label costs a space and itself
        label_width = min(longest, spare)
        if label_width >= min(MIN_LABEL, longest):
            layout = replace(layout, label_width=label_width)
    return layout


def widths_wanted(rows: Mapping[VarRef, RowView]) -> tuple[int, int]:
    """The columns the grid of these rows needs for 16 bits a line (bare digits, as at
    80 columns), and the most it can use (the symbols, the gap between bytes, its labels
    at their longest): what a panel beside the table needs and can use (0, 0: no IO)."""
    bits = bits_from_rows(rows, 0.0)
    if not bits:
        return 0, 0
    index_width = max(3, *(len(str(index)) for index in bits))
    least = Layout(16, index_width, sep=1, glyph=False).width
    most = choose_layout(UNBOUNDED, bits, (bit.label for bit in bits.values())).width
    return least, most


#: A width no terminal has: the layout a grid takes when nothing limits it.
UNBOUNDED = 100_000


def bit_style(
    bit: Bit, cursor: bool = False, pending: bool = False, change: ChangeStyle = CHANGED_DARK
) -> str:
    """The style that alone tells a cell's state (see the module's table); ``change``
    is the change highlight of the theme it is drawn in."""
    on = bit.state is BitState.ON
    if bit.state is BitState.UNWATCHED:
        parts = [STYLE_UNWATCHED]
    elif not bit.has_value:
        parts = [STYLE_UNKNOWN, "italic" if bit.stale else ""]
    elif cursor:
        parts = [STYLE_CURSOR_ON if on else "", "italic" if bit.stale else ""]
    elif bit.stale:
        parts = [STYLE_STALE_ON if on else STYLE_STALE]
    elif bit.changed:
        parts = [change.bit_on if on else change.bit_off]
    else:
        parts = [STYLE_ON if on else STYLE_OFF]
    if cursor:
        parts.append(STYLE_CURSOR)
    if pending:
        parts.append(STYLE_PENDING)
    return " ".join(part for part in parts if part)


def cell_text(bit: Bit, layout: Layout) -> str:
    """``128`` (no symbol: the style tells the state), ``●128``, ``○129 vacuum``,
    ``?130`` (no value), ``  ·`` (not watched); the digits are right-aligned, the symbol
    just before them (``  ●5``)."""
    digits = 1 + layout.index_width if layout.glyph else layout.index_width
    if bit.state is BitState.UNWATCHED:
        return f"{GLYPH_UNWATCHED:>{digits}}".ljust(layout.cell_width)
    glyph = ""
    if layout.glyph:
        glyph = {
            BitState.ON: GLYPH_ON,
            BitState.OFF: GLYPH_OFF,
            BitState.UNKNOWN: GLYPH_UNKNOWN,
        }[bit.state]
    text = f"{glyph}{bit.index}".rjust(digits)
    if layout.label_width:
        text += " " + fit_label(bit.label, layout.label_width)
    return text


def fit_label(label: str, width: int) -> str:
    """The label made safe, cut with ``…`` to ``width`` cells (wide characters count 2)."""
    safe = terminal_safe(label)
    if cell_len(safe) > width:
        safe = set_cell_size(safe, width - 1) + "…"
    return set_cell_size(safe, width)


def word_text(word: Word, gap: int = 2, change: ChangeStyle = CHANGED_DARK) -> Text:
    text = Text(" " * (gap + word.pad))
    text.append(word.hex_text(), style=STYLE_HEX)
    digits = len(str((1 << word.width) - 1))
    text.append(f" {word.dec_text():>{digits}}")
    if word.stale:
        text.stylize(STYLE_STALE, gap + word.pad)
    elif word.changed:
        text.stylize(change.value, gap + word.pad)
    return text


def render_grid(
    lines: list[GridLine],
    layout: Layout,
    cursor: int | None = None,
    pending: frozenset[int] = frozenset(),
    change: ChangeStyle = CHANGED_DARK,
) -> Text:
    """The grid as one Text, a line per :class:`GridLine`, the blanks between cells
    unstyled; ``cursor`` (an index) and the bits with a write in flight (``pending``)
    drawn as :func:`bit_style` says, a change with ``change`` (the theme's)."""
    text = Text(no_wrap=True, overflow="crop", end="")
    for n, line in enumerate(lines):
        if n:
            text.append("\n")
        for k, bit in enumerate(line.bits):
            if k:
                text.append(" " * layout.sep)
                if k == 8 and layout.byte_gap:
                    text.append(" " * layout.byte_gap)
            style = bit_style(bit, bit.index == cursor, bit.index in pending, change)
            text.append(cell_text(bit, layout), style=style)
        text.append_text(word_text(line.word, layout.word_gap, change))
    return text


@dataclass(frozen=True, slots=True)
class Grid:
    """What the panel draws: the lines, the layout they were made for, the text."""

    lines: tuple[GridLine, ...]
    layout: Layout
    text: Text

    def bit(self, index: int) -> Bit | None:
        for line in self.lines:
            if line.start <= index < line.start + len(line.bits):
                return line.bits[index - line.start]
        return None


def build_grid(
    rows: Mapping[VarRef, RowView],
    now: float,
    width: int,
    cursor: int | None = None,
    pending: frozenset[int] = frozenset(),
    change: ChangeStyle = CHANGED_DARK,
) -> Grid:
    """The grid of the watched IO rows for a panel ``width`` columns wide, a change
    highlighted with ``change`` (the theme's)."""
    bits = bits_from_rows(rows, now)
    layout = choose_layout(width, bits, (bit.label for bit in bits.values()))
    lines = grid_lines(bits, layout.per_line)
    return Grid(tuple(lines), layout, render_grid(lines, layout, cursor, pending, change))
