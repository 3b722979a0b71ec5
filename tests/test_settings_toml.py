"""The ``[settings]`` table rewritten as a user wrote it: each file below is one a user
may keep (by hand, from another tool, on Windows), and the save changes the values set
and not one other byte of it."""

from __future__ import annotations

import tomllib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rac_console.commands.settings import SETTINGS_KEYS, Value, update_settings_text

SOURCE = "/home/op/.config/rac-console/config.toml"


def rewritten(text: str, values: dict[str, Value]) -> str:
    """The text saved with ``values``, which the file then holds, and nothing else new."""
    new = update_settings_text(text, values, SOURCE)
    before = tomllib.loads(text)
    before["settings"] = {**before.get("settings", {}), **values}
    assert tomllib.loads(new) == before
    return new


# Each: the file, the settings saved, the file after. Everything not a value set is kept.
REWRITES = {
    "settings as dotted keys at the top, one replaced and one added beside it": (
        '# mine\nsettings.theme = "nord"  # my theme\n\n[target.bench]\nhost = "h"\n',
        {"theme": "dracula", "hex_view": True},
        '# mine\nsettings.theme = "dracula"  # my theme\nsettings.hex_view = true\n\n'
        '[target.bench]\nhost = "h"\n',
    ),
    "settings as an inline table": (
        'settings = { theme = "nord", io_grid = true  }  # short\n',
        {"theme": "dracula", "hex_view": True},
        'settings = { theme = "dracula", io_grid = true, hex_view = true  }  # short\n',
    ),
    "a comment and indent after a one-line value of another kind": (
        "[settings]\n  \"theme\" = '''nord'''  # triple\n  io_grid = [true]  # a list\n",
        {"theme": "dracula", "io_grid": False},
        '[settings]\n  "theme" = "dracula"  # triple\n  io_grid = false  # a list\n',
    ),
    "a quoted key with an escape in it": (
        '[settings]\n"the\\u006De" = "nord"\n',
        {"theme": "dracula"},
        '[settings]\n"the\\u006De" = "dracula"\n',
    ),
    # Right before tomlkit too; no test held them.
    "a quoted key and a header with spaces": (
        '[ settings ]  # look\n"theme" = "nord"\n',
        {"theme": "dracula", "hex_view": True},
        '[ settings ]  # look\n"theme" = "dracula"\nhex_view = true\n',
    ),
    "a string holding # and ], an inline table holding them too": (
        '[settings]\ntheme = "a]#b"  # c\nmine = { a = "]", b = "#" }\n',
        {"theme": "nord", "frame_gaps": False},
        '[settings]\ntheme = "nord"  # c\nmine = { a = "]", b = "#" }\nframe_gaps = false\n',
    ),
    "a new key before the comments and blank lines that lead into the next table": (
        '[settings]\ntheme = "nord"\n\n# the bench, last\n[target.bench]\nhost = "h"\n',
        {"hex_view": True},
        '[settings]\ntheme = "nord"\nhex_view = true\n\n# the bench, last\n[target.bench]\n'
        'host = "h"\n',
    ),
    "an empty table gets its keys right under its header": (
        '[settings]\n\n# the bench\n[target.bench]\nhost = "h"\n',
        {"io_grid": False},
        '[settings]\nio_grid = false\n\n# the bench\n[target.bench]\nhost = "h"\n',
    ),
    "an array of tables after the table": (
        '[settings]\ntheme = "nord"\n\n[[watch]]\ntype = "I"\nindex = 1\n',
        {"theme": "dracula", "hex_view": True},
        '[settings]\ntheme = "dracula"\nhex_view = true\n\n[[watch]]\ntype = "I"\nindex = 1\n',
    ),
    "the table last, without a final newline": (
        '[target.bench]\nhost = "h"\n\n[settings]\ntheme = "nord"  # c',
        {"theme": "dracula", "hex_view": True},
        '[target.bench]\nhost = "h"\n\n[settings]\ntheme = "dracula"  # c\nhex_view = true\n',
    ),
    "Windows line ends: a key replaced and one added": (
        '# mine\r\n[settings]\r\ntheme = "nord"\r\n\r\n[target.bench]\r\nhost = "h"\r\n',
        {"theme": "dracula", "hex_view": True},
        '# mine\r\n[settings]\r\ntheme = "dracula"\r\nhex_view = true\r\n\r\n'
        '[target.bench]\r\nhost = "h"\r\n',
    ),
    "sub-tables of settings after the table, one of them empty": (
        '[settings]\ntheme = "nord"\n# mine\n[settings.mine]\na = 1\n[settings.more]\n',
        {"io_grid": True},
        '[settings]\ntheme = "nord"\nio_grid = true\n# mine\n[settings.mine]\na = 1\n'
        "[settings.more]\n",
    ),
}


@pytest.mark.parametrize(("before", "values", "after"), REWRITES.values(), ids=list(REWRITES))
def test_only_the_values_set_change(before: str, values: dict[str, Value], after: str) -> None:
    assert rewritten(before, values) == after


# ------------------------------------------- any layout of the table, any values


KEYS = sorted(SETTINGS_KEYS)


def a_value(key: str) -> st.SearchStrategy[Value]:
    if SETTINGS_KEYS[key] is bool:
        return st.booleans()
    return st.sampled_from(["nord", "a#b", "x]y", "it's", 'q"uote'])


values_set = st.lists(st.sampled_from(KEYS), min_size=1, unique=True).flatmap(
    lambda keys: st.fixed_dictionaries({key: a_value(key) for key in keys})
)
held = st.dictionaries(st.sampled_from([*KEYS, "mine"]), st.booleans(), max_size=4)


@st.composite
def config_files(draw: st.DrawFn) -> str:
    """A config file as users write them: a table (a sub-table after it, or none),
    dotted keys or an inline table for the settings, comments beside and between, other
    tables around, LF or CRLF, a final line end or none."""
    keys = draw(held)
    form = draw(st.sampled_from(["table", "dotted", "inline"]))
    comment = st.sampled_from(["", "  # mine", "\t# x = [1"])
    if form == "table":
        lines = ["[settings]" + draw(comment)]
        for key, value in keys.items():
            lines += draw(st.sampled_from([[], ["# about " + key], [""]]))
            lines.append(f"{key} = {str(value).lower()}" + draw(comment))
        lines += draw(st.sampled_from([[], [""], ["", "# the next table"]]))
        lines += draw(st.sampled_from([[], ["[settings.extra]", "a = 1"]]))
    elif form == "dotted":
        lines = [
            f"settings.{key} = {str(value).lower()}" + draw(comment) for key, value in keys.items()
        ]
    else:
        pairs = ", ".join(f"{key} = {str(value).lower()}" for key, value in keys.items())
        lines = [f"settings = {{ {pairs} }}" + draw(comment)]
    before = ["# rac-console", 'top = "t"', ""] if form == "dotted" else ["# rac-console", ""]
    after = draw(
        st.sampled_from([[], ["[target.bench]", 'host = "h"'], ["[[watch]]", "index = 1"]])
    )
    newline = draw(st.sampled_from(["\n", "\r\n"]))
    return newline.join(before + lines + ([""] if after else []) + after) + draw(
        st.sampled_from([newline, ""])
    )


@settings(deadline=None, max_examples=200)
@given(config_files(), values_set)
def test_any_layout_is_rewritten_keeping_every_line_not_set(text: str, values: dict) -> None:
    new = rewritten(text, values)
    ending = "\r\n" if "\r\n" in text else "\n"
    assert new.count("\r\n") == (new.count("\n") if ending == "\r\n" else 0)
    kept = iter(new.split(ending))
    for line in text.split(ending):
        if not any(key in line for key in [*values, "settings = {"]):  # no value set there
            assert line in kept  # there, and in the same order (`in` moves the iterator on)
