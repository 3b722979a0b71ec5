"""What a profile looks like where the target is shown: the status line's label in the
profile's colour and the writes mode, and the REPL's prompt and toolbar. A colour no
front end knows falls back to default colours; text from the config file is escaped."""

from __future__ import annotations

from dataclasses import replace

import pytest
from rich.color import Color

from rac_console.present.status import label_style, profile_colour, status_text, target_label
from tests.support.samples import CELL3, SIM


def span_styles(line, text: str) -> list[str]:
    """The styles of the spans that cover ``text`` in a rich Text."""
    start = line.plain.index(text)
    return [str(span.style) for span in line.spans if span.start <= start and span.end > start]


def test_the_simulator_says_writes_open() -> None:
    line = status_text(SIM, None, 0.0)
    assert line.plain.startswith(" SIMULATOR (built-in)  writes open ")


def test_a_profile_shows_its_label_in_its_colour_then_the_target_and_writes() -> None:
    line = status_text(CELL3, None, 0.0)
    assert line.plain.startswith(" Cell 3 — welding   LIVE 192.168.0.1:5006   CONFIRM WRITES ")
    (style,) = span_styles(line, "Cell 3")
    assert "on #800000" in style  # red as truecolor: a theme cannot dull it
    assert "writes open" not in line.plain


def test_read_only_is_the_one_badge_it_always_was() -> None:
    line = status_text(replace(CELL3, writes="read-only", read_only=True), None, 0.0).plain
    assert " READ-ONLY " in line
    assert "CONFIRM" not in line and "writes open" not in line


def test_a_profile_with_no_label_shows_its_name() -> None:
    line = status_text(replace(CELL3, label=None, colour=None), None, 0.0)
    assert line.plain.startswith(" cell3   LIVE")
    (style,) = span_styles(line, "cell3")
    assert "reverse" in style


@pytest.mark.parametrize("colour", ["no_such_colour", "#zzzzzz", "", None])
def test_an_unknown_colour_falls_back_and_never_crashes(colour: str | None) -> None:
    assert profile_colour(colour) is None
    line = status_text(replace(CELL3, colour=colour), None, 0.0)
    assert line.plain.startswith(" Cell 3 — welding ")
    assert "reverse" in str(label_style(colour))


def test_colours_rich_knows_and_ink_that_reads_on_them() -> None:
    assert profile_colour("bright_red") == Color.parse("bright_red")
    assert profile_colour("#00ff7f") == Color.parse("#00ff7f")
    assert label_style("yellow").color == Color.parse("#000000")
    assert label_style("#000080").color == Color.parse("#ffffff")
    assert label_style("yellow").bold


def test_a_label_from_the_config_file_is_escaped_and_cut() -> None:
    hostile = replace(CELL3, label="\x1b[2Jevil\x07 label")
    line = status_text(hostile, None, 0.0).plain
    assert "\x1b" not in line and "\x07" not in line
    assert "\\x1b[2Jevil\\x07 label" in line
    long = target_label(replace(CELL3, label="L" * 80))
    assert long is not None and len(long) == 32 and long.endswith("…")
    assert target_label(SIM) is None
