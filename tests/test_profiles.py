"""Target profiles: the config file's ``[target.NAME]`` tables, parsed and loaded.

The parser is pure (a dict in, profiles out); the loader reads the TOML file named by
RAC_CONSOLE_CONFIG (or the user's config directory). Every problem is one line that
names the file, the profile and the key, and says how to write it.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

from rac_console.commands.policy import AllowRange, WritePolicy, Writes
from rac_console.commands.profiles import colour_syntax_ok, parse_config
from rac_console.engine.setup.config import CONFIG_ENV, config_path, load_config
from rac_console.protocol import InputError, kind_of

SOURCE = "/etc/rac/config.toml"

CELL3 = {
    "host": "192.168.0.1",
    "port": 5007,
    "label": "Cell 3 — welding",
    "colour": "red",
    "writes": "confirm",
    "allow": ["I 100-199", "IO 64-71"],
}


def profiles(data: dict[str, object]):
    return parse_config(data, SOURCE).profiles


def refusal(data: dict[str, object]) -> str:
    with pytest.raises(InputError) as caught:
        parse_config(data, SOURCE)
    text = str(caught.value)
    assert "\n" not in text
    assert text.startswith(f"{SOURCE}: ")
    return text


# ----------------------------------------------------------------- the parser


def test_a_full_profile() -> None:
    cell3 = profiles({"target": {"cell3": CELL3}})["cell3"]
    assert (cell3.name, cell3.host, cell3.port) == ("cell3", "192.168.0.1", 5007)
    assert (cell3.label, cell3.colour) == ("Cell 3 — welding", "red")
    assert cell3.policy == WritePolicy(
        Writes.CONFIRM,
        (AllowRange(kind_of("I"), 100, 199), AllowRange(kind_of("IO"), 64, 71)),
        "profile cell3",
    )


def test_defaults_port_5006_writes_open_any_variable() -> None:
    bare = profiles({"target": {"bench": {"host": "10.0.0.9"}}})["bench"]
    assert (bare.port, bare.label, bare.colour) == (5006, None, None)
    assert bare.policy.writes is Writes.OPEN
    assert bare.policy.allow is None


def test_color_is_accepted_too_and_colours_are_lowercased() -> None:
    found = profiles(
        {
            "target": {
                "a": {"host": "h", "color": "Bright_Red"},
                "b": {"host": "h", "colour": "#A0B1C2"},
            }
        }
    )
    assert (found["a"].colour, found["b"].colour) == ("bright_red", "#a0b1c2")


def test_read_only_and_an_empty_allow_list() -> None:
    found = profiles({"target": {"ro": {"host": "h", "writes": "read-only", "allow": []}}})
    assert found["ro"].policy.writes is Writes.READ_ONLY
    assert found["ro"].policy.allow == ()


def test_a_missing_target_table_means_no_profiles_and_settings_are_kept() -> None:
    parsed = parse_config({"settings": {"theme": "nord", "frames": {"hex": True}}}, SOURCE)
    assert parsed.profiles == {}
    assert parsed.settings == {"theme": "nord", "frames": {"hex": True}}
    assert parse_config({}, SOURCE).settings == {}


@pytest.mark.parametrize(
    ("data", "says"),
    [
        (
            {"target": {"cell3": {"host": "h", "colur": "red"}}},
            "[target.cell3] unknown key 'colur': use host, port, label, colour (or color), "
            "writes, allow",
        ),
        ({"target": {"cell3": {"label": "x"}}}, '[target.cell3] has no host: add host = "'),
        ({"target": {"cell3": {"host": ""}}}, '[target.cell3] host: write host = "192.168.0.1"'),
        ({"target": {"cell3": {"host": 10}}}, '[target.cell3] host: write host = "192.168.0.1"'),
        ({"target": {"cell3": {"host": "a b"}}}, "[target.cell3] host"),
        (
            {"target": {"cell3": {"host": "h", "port": "5006"}}},
            "[target.cell3] port: write port = 5006",
        ),
        ({"target": {"cell3": {"host": "h", "port": 70000}}}, "from 1 to 65535"),
        ({"target": {"cell3": {"host": "h", "port": True}}}, "[target.cell3] port"),
        ({"target": {"cell3": {"host": "h", "label": 3}}}, '[target.cell3] label: write label = "'),
        (
            {"target": {"cell3": {"host": "h", "writes": "maybe"}}},
            '[target.cell3] writes = \'maybe\': write writes = "open", "confirm" or "read-only"',
        ),
        ({"target": {"cell3": {"host": "h", "writes": True}}}, "[target.cell3] writes"),
        (
            {"target": {"cell3": {"host": "h", "allow": "I 1-5"}}},
            '[target.cell3] allow: write a list, allow = ["I 100-199", "IO 64-71"]',
        ),
        ({"target": {"cell3": {"host": "h", "allow": [5]}}}, "[target.cell3] allow: write a list"),
        (
            {"target": {"cell3": {"host": "h", "allow": ["X 1-5"]}}},
            "[target.cell3] allow: allow 'X 1-5': X is not a variable type",
        ),
        ({"target": {"cell3": {"host": "h", "allow": ["I 9-1"]}}}, "[target.cell3] allow"),
        (
            {"target": {"cell3": {"host": "h", "colour": "light red"}}},
            "[target.cell3] colour 'light red': write a colour name or \"#rrggbb\"",
        ),
        ({"target": {"cell3": {"host": "h", "colour": "#12345"}}}, "[target.cell3] colour"),
        ({"target": {"cell3": {"host": "h", "colour": 1}}}, "[target.cell3] colour"),
        (
            {"target": {"cell3": {"host": "h", "colour": "red", "color": "blue"}}},
            "[target.cell3] has colour and color: keep one",
        ),
        (
            {"target": {"cell3": "192.168.0.1"}},
            "[target.cell3] is not a table: write [target.cell3]",
        ),
        ({"target": {"host": "h"}}, "[target] holds one table per profile"),
        ({"target": "cell3"}, "[target] holds one table per profile"),
        ({"target": {"a b": {"host": "h"}}}, "profile name 'a b'"),
        ({"target": {"sim": {"host": "h"}}}, "'sim' names the built-in simulator"),
        (
            {"targets": {"cell3": {"host": "h"}}},
            "unknown table or key 'targets': use [target.NAME]",
        ),
        ({"settings": 3}, "[settings] is a table"),
    ],
)
def test_every_problem_is_one_line_naming_the_file_profile_and_key(
    data: dict[str, object], says: str
) -> None:
    assert says in refusal(data)


def test_text_from_the_file_is_escaped_in_messages() -> None:
    text = refusal({"target": {"cell3": {"host": "h", "writes": "x\x1b[2J"}}})
    assert "\x1b" not in text


@pytest.mark.parametrize("colour", ["red", "bright_red", "grey35", "#00ff7f", "Red", "color(9)"])
def test_colour_syntax(colour: str) -> None:
    assert colour_syntax_ok(colour) == (colour != "color(9)")


@pytest.mark.parametrize("colour", ["", "#12345", "#gggggg", "light red", "red;", "9red"])
def test_colour_syntax_refused(colour: str) -> None:
    assert not colour_syntax_ok(colour)


# ----------------------------------------------------------------- the file


def test_the_path_is_the_env_var_or_the_user_config_dir(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv(CONFIG_ENV, raising=False)
    if sys.platform == "win32":  # %LOCALAPPDATA%, as the README says (test_portability)
        assert config_path().parts[-3:] == ("rac-console", "rac-console", "config.toml")
    else:
        assert config_path() == Path(tmp_path / "home" / ".config" / "rac-console" / "config.toml")
    monkeypatch.setenv(CONFIG_ENV, str(tmp_path / "mine.toml"))
    assert config_path() == tmp_path / "mine.toml"


def test_a_missing_file_means_no_profiles(tmp_path: Path) -> None:
    config = load_config(tmp_path / "absent.toml")
    assert config.profiles == {} and config.settings == {}
    assert not config.found


def test_the_file_is_loaded(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_text(
        '[settings]\ntheme = "nord"\n\n[target.cell3]\nhost = "192.168.0.1"\n'
        'label = "Cell 3 — welding"\ncolour = "red"\nwrites = "confirm"\n'
        'allow = ["I 100-199"]\n',
        encoding="utf-8",
    )
    config = load_config(path)
    assert config.found and config.path == path
    assert config.profiles["cell3"].policy.confirms
    assert config.settings == {"theme": "nord"}


def test_a_toml_syntax_error_gives_its_line(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_text('[target.cell3]\nhost = "192.168.0.1"\nport = \n', encoding="utf-8")
    with pytest.raises(InputError) as caught:
        load_config(path)
    text = str(caught.value)
    assert text.startswith(f"{path}: not valid TOML")
    assert "line 3" in text and "\n" not in text


def test_a_file_problem_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_text('[target.cell3]\nhost = "h"\nwrites = "sometimes"\n', encoding="utf-8")
    with pytest.raises(InputError, match=rf"^{re.escape(str(path))}: \[target.cell3\] writes"):
        load_config(path)
    path.write_bytes(b'[target.cell3]\nhost = "\xff"\n')
    with pytest.raises(InputError, match="not a UTF-8 text file"):
        load_config(path)
    with pytest.raises(InputError, match="is not a regular file"):
        load_config(tmp_path)


# ----------------------------------------------------------------- completion


def test_connect_completes_sim_and_the_profiles() -> None:
    from rac_console.present.completion import complete

    targets = [("cell3", "Cell 3 — welding"), ("cell4", "192.168.0.4")]
    found = [(c.text, c.help) for c in complete("connect ", (), targets)]
    assert found == [
        ("sim", "the built-in simulator"),
        ("cell3", "Cell 3 — welding"),
        ("cell4", "192.168.0.4"),
    ]
    assert [c.text for c in complete("connect ce", (), targets)] == ["cell3", "cell4"]
    assert [c.text for c in complete("connect s")] == ["sim"]
    assert complete("connect cell3 ", (), targets) == []
