"""What a row and the I/O grid say, in words a reader takes as meant: a variable never
read is not "stale" (nothing old is shown), and a grid of eight bits shows their byte."""

from __future__ import annotations

from rac_console.commands.language import VarRef
from rac_console.engine.watch.rows import WatchRow
from rac_console.present.table_cells import status_cell
from rac_console.protocol import KINDS, VT, Variant


def test_a_variable_never_read_is_an_error_not_a_stale_value() -> None:
    row = WatchRow(VarRef(KINDS["P"], 200))
    row.fail("E_INVALIDARG", now=1.0)
    shown = status_cell(row.view())
    assert shown.plain == "E_INVALIDARG"
    assert "red" in str(shown.style)
    row.update(Variant(VT.R4, 1.0), now=2.0)
    row.fail("TIMEOUT", now=3.0)  # a value was shown: now it is stale
    assert status_cell(row.view()).plain == "TIMEOUT (stale)"


def test_the_history_keeps_each_line_once_at_its_last_use(tmp_path) -> None:
    """The docs say the last 1,000 distinct commands: Up walks each line once."""
    from rac_console.present.history import History

    history = History(tmp_path / "history")
    for line in ("get I 1", "get I 2", "get I 1", "watch IO 0-7", "get I 2"):
        history.append(line)
    assert history.entries == ["get I 1", "watch IO 0-7", "get I 2"]
    assert History(tmp_path / "history").entries == ["get I 1", "watch IO 0-7", "get I 2"]
