"""One test per tomlkit hook in ``rac_console.commands.tomlkit_compat``: each fails when
tomlkit moves what the settings' rewrite relies on beneath its public API."""

from __future__ import annotations

import importlib.metadata
import tomllib
from pathlib import Path

import tomlkit
from packaging.requirements import Requirement
from tomlkit.items import InlineTable, Table

from rac_console.commands import tomlkit_compat

ROOT = Path(__file__).resolve().parent.parent

HEAD = '[settings]\ntheme = "nord"  # mine\n'
# After the last key: a blank line and the comment leading into what comes next, a
# sub-table and an array of tables of settings; then the next table.
TAIL = "\n# next\n[settings.sub]\na = 1\n[[settings.list]]\nb = 2\n"
NEXT = '\n[target.bench]\nhost = "h"\n'
FILE = HEAD + TAIL + NEXT


def settings_of(text: str) -> tuple[tomlkit.TOMLDocument, Table]:
    document = tomlkit.parse(text)
    table = document["settings"]
    assert isinstance(table, Table)
    return document, table


def test_take_tail_takes_the_comments_blanks_and_sub_tables_after_the_last_key() -> None:
    document, table = settings_of(FILE)
    tail = tomlkit_compat.take_tail(table)
    # Drawn without them: the comment and blank line had no key, the sub-tables are
    # tables; the last key and its comment stay, and so does the next table.
    assert document.as_string() == HEAD + '[target.bench]\nhost = "h"\n'
    assert [key.key for key, _ in tail if key is not None] == ["sub", "list"]
    assert any(key is None and "# next" in item.as_string() for key, item in tail)
    assert table["theme"] == "nord"


def test_put_back_draws_the_tail_after_the_table_items_again() -> None:
    document, table = settings_of(FILE)
    tail = tomlkit_compat.take_tail(table)
    tomlkit_compat.put_back(table, tail)
    assert document.as_string() == FILE  # drawn from the list, in its order
    tail = tomlkit_compat.take_tail(table)
    table.append("io_grid", True)
    tomlkit_compat.put_back(table, tail)
    assert document.as_string() == HEAD + "io_grid = true\n" + TAIL + NEXT


def test_new_keys_go_right_after_the_last_key_of_a_table_and_an_inline_table() -> None:
    document, table = settings_of(FILE)
    tomlkit_compat.append_after_last_key(table, {"io_grid": True, "theme_too": "x"})
    assert document.as_string() == HEAD + 'io_grid = true\ntheme_too = "x"\n' + TAIL + NEXT
    inline = tomlkit.parse('settings = { theme = "nord"  }  # short\n')
    assert isinstance(inline["settings"], InlineTable)
    tomlkit_compat.append_after_last_key(inline["settings"], {"hex_view": True})
    assert inline.as_string() == 'settings = { theme = "nord", hex_view = true  }  # short\n'


def test_tomlkit_here_is_a_version_the_hooks_were_checked_against() -> None:
    supported = Requirement(tomlkit_compat.SUPPORTED)
    assert supported.specifier.contains(importlib.metadata.version("tomlkit"))
    assert supported.specifier.contains(tomlkit_compat.CHECKED_WITH)
    assert not supported.specifier.contains("0.16")  # an upper bound: an upgrade is checked


def test_pyproject_allows_the_versions_the_hooks_were_checked_against() -> None:
    with open(ROOT / "pyproject.toml", "rb") as file:
        dependencies = tomllib.load(file)["project"]["dependencies"]
    assert tomlkit_compat.SUPPORTED in dependencies
