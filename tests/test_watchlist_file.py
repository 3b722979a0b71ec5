"""A watch list saved to a file comes back as it was; a file that is not one is refused."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from rac_console.commands.language import VarRef
from rac_console.engine.watch import watchlist
from rac_console.protocol import InputError, kind_of


def var(code: str, index: int) -> VarRef:
    return VarRef(kind_of(code), index)


ROWS = [
    (var("P", 10), "pick every time", 2.5),
    (var("IO", 128), "gripper", None),
    (var("IO", 129), "gripper", None),
    (var("S", 1), 'say "hi" \\ back\tslash \u00e9', 0.1),
    (var("I", 0), "", None),
    (var("J", 32767), "", 3600.0),
    (var("F", 7), "", 0.0),
]


def test_save_then_load_gives_the_same_rows_in_the_same_order(tmp_path: Path) -> None:
    path = tmp_path / "cell3.toml"
    watchlist.save(path, ROWS)
    loaded = watchlist.load(path)
    assert loaded == ROWS
    assert all(every is None or type(every) is float for _, _, every in loaded)


def test_the_saved_file_is_plain_toml_one_table_per_row(tmp_path: Path) -> None:
    path = tmp_path / "cell3.toml"
    watchlist.save(path, ROWS)
    tables = tomllib.loads(path.read_text(encoding="utf-8"))["watch"]
    assert len(tables) == len(ROWS)
    assert tables[0] == {"type": "P", "index": 10, "label": "pick every time", "every": 2.5}
    assert tables[1] == {"type": "IO", "index": 128, "label": "gripper"}
    assert tables[4] == {"type": "I", "index": 0}  # no empty label, no every


def test_an_empty_watch_list_round_trips(tmp_path: Path) -> None:
    path = tmp_path / "empty.toml"
    watchlist.save(path, [])
    assert watchlist.load(path) == []


def test_a_hand_written_file_is_read_as_meant(tmp_path: Path) -> None:
    path = tmp_path / "hand.toml"
    path.write_text(
        '[[watch]]\ntype = "io"\nindex = 5\nevery = 2\n\n'
        "[[watch]]\ntype = 'T'\nindex = 0\nlabel = 'tool'\n",
        encoding="utf-8",
    )
    assert watchlist.load(path) == [(var("IO", 5), "", 2.0), (var("T", 0), "tool", None)]


def test_an_unknown_key_is_named_with_its_entry_and_the_keys_allowed(tmp_path: Path) -> None:
    path = tmp_path / "typo.toml"
    path.write_text(
        '[[watch]]\ntype = "I"\nindex = 1\n\n[[watch]]\ntype = "I"\nindex = 2\nlable = "x"\n',
        encoding="utf-8",
    )
    with pytest.raises(InputError) as info:
        watchlist.load(path)
    assert str(info.value) == (
        "watch entry 2 has an unknown key 'lable': use type, index, label, every"
    )


def test_a_row_written_twice_is_refused_even_spelled_differently(tmp_path: Path) -> None:
    path = tmp_path / "twice.toml"
    watchlist.save(path, [(var("P", 3), "pick", None), (var("J", 3), "", None)])
    path.write_text(
        path.read_text(encoding="utf-8") + '\n[[watch]]\ntype = "p"\nindex = 3\nlabel = "place"\n',
        encoding="utf-8",
    )
    with pytest.raises(InputError) as info:
        watchlist.load(path)
    assert str(info.value) == "watch entry 3 repeats P3 (entry 1)"


def test_a_bad_type_or_index_names_its_entry(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('[[watch]]\ntype = "Q"\nindex = 1\n', encoding="utf-8")
    with pytest.raises(InputError, match="watch entry 1: unknown variable type 'Q'"):
        watchlist.load(path)
    path.write_text('[[watch]]\ntype = "I"\nindex = 40000\n', encoding="utf-8")
    with pytest.raises(InputError, match="watch entry 1: index 40000 is too large"):
        watchlist.load(path)


def test_files_that_cannot_be_written_or_read_are_one_clear_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot write"):
        watchlist.save(tmp_path / "no" / "such" / "dir.toml", ROWS)
    with pytest.raises(InputError, match="cannot read"):
        watchlist.load(tmp_path / "missing.toml")
    with pytest.raises(InputError, match="not a regular file"):
        watchlist.load(tmp_path)
