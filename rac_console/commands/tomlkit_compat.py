"""Every tomlkit hook the settings' rewrite uses that tomlkit does not promise. Pure.

tomlkit documents keeping a file's layout, not how a table holds its items. Putting a
new key right after a table's last key (:func:`append_after_last_key`, for
:mod:`rac_console.commands.settings`) relies on two things beneath its public API: a
table's items are the list ``table.value.body`` of ``(key, item)`` pairs, a comment or
blank line with the key None (:func:`take_tail`), and the document is drawn from that
list in order, so an item put back on it is drawn there without tomlkit's index by key
being told (:func:`put_back`). Keeping them here means an upgrade is checked here, and
``tests/test_tomlkit_compat.py`` fails (one test per hook) when one moves; the range in
pyproject.toml is :data:`SUPPORTED`. A tomlkit that breaks a hook all the same makes the
save refused, not wrong: the settings' rewrite parses its result again.
"""

from __future__ import annotations

from collections.abc import Mapping

from tomlkit.items import AoT, InlineTable, Item, Key, Table

#: The tomlkit versions these hooks hold for (pyproject.toml says the same): 0.10 the
#: lowest tested, 0.15.0 and 0.15.1 wrote some inline tables and escapes wrong.
SUPPORTED = "tomlkit>=0.10,!=0.15.0,!=0.15.1,<0.16"

#: The tomlkit version these hooks were last checked against.
CHECKED_WITH = "0.15.3"

#: What follows a table's last key: ``(key, item)`` pairs in the file's order.
Tail = list[tuple[Key | None, Item]]


def take_tail(table: Table | InlineTable) -> Tail:
    """What follows ``table``'s last key, taken off its items and returned in order:
    the comments and blank lines (key None in ``table.value.body``), which lead into
    what comes next, and its sub-tables and arrays of tables. Checked with tomlkit 0.15.3."""
    body = table.value.body
    cut = len(body)
    while cut and (body[cut - 1][0] is None or isinstance(body[cut - 1][1], Table | AoT)):
        cut -= 1
    tail = body[cut:]
    del body[cut:]
    return tail


def put_back(table: Table | InlineTable, tail: Tail) -> None:
    """``tail`` after ``table``'s items again, drawn there when the document is rendered
    (tomlkit's index by key is not told: render the document, look nothing up).
    Checked with tomlkit 0.15.3."""
    table.value.body.extend(tail)


def append_after_last_key(table: Table | InlineTable, values: Mapping[str, object]) -> None:
    """``values`` added to ``table`` right after its last key. tomlkit's own append puts
    them after the comments that follow it (they lead into the next table) and a blank
    line before a sub-table. Render the document next; look nothing up in it."""
    tail = take_tail(table)
    for key, value in values.items():
        table.append(key, value)
    put_back(table, tail)
