"""The config file's ``[settings]`` table: read, and rewritten in the file's text. Pure.

The console keeps its look there (read by :mod:`rac_console.engine.setup.settings`)::

    [settings]
    theme = "textual-light"   # Ctrl+P, Theme
    io_grid = true            # F5: the I/O grid shown
    poll_frames = false       # F3: poll frames in the log
    hex_view = true           # F7: each frame's bytes in hex
    frame_gaps = true         # t in the log: the time since the previous frame

The file is the user's: :func:`update_settings_text` changes the values set and keeps
every other byte (comments, blank lines, order, quoting, line ends). tomlkit does the
rewriting because it is made for it: its document keeps the file's layout, so a value
is replaced where it stands however the user wrote the table (a ``[settings]`` table,
dotted ``settings.theme`` keys, an inline table, a value over several lines, quoted
keys). Our own rewriter before it (regular expressions over the lines, 285 lines)
refused some of these and dropped the comment after others. Two of tomlkit's habits
are undone here: a new key goes right after the table's last key (tomlkit puts it
after the comments that follow, which lead into the next table; done through
:mod:`.tomlkit_compat`, which holds what this needs beneath tomlkit's public API), and
new lines take the file's Windows line ends. The result is parsed again (tomllib) and must hold what
the file held with only those values changed, whatever tomlkit's version did; a file
that is not valid TOML, or whose ``settings`` is no table, is an InputError of one line,
and the file is left as it is. tomlkit is imported for a save only: reading the
settings at start needs none of it.
"""

from __future__ import annotations

import tomllib
from collections.abc import Collection, Mapping, MutableMapping

from ..protocol import InputError
from .tomltext import parse_toml

#: A setting's value: only simple types are ever written.
Value = str | bool

#: The settings the console knows, and the type of each.
SETTINGS_KEYS: dict[str, type[str] | type[bool]] = {
    "theme": str,
    "io_grid": bool,
    "poll_frames": bool,
    "hex_view": bool,
    "frame_gaps": bool,
}
_KNOWN_TEXT = ", ".join(SETTINGS_KEYS)


def read_settings(
    table: Mapping[str, object], source: str, themes: Collection[str] | None = None
) -> tuple[dict[str, Value], list[str]]:
    """The known settings of a ``[settings]`` table with the right type (and a theme
    among ``themes``, when given), and a line (led by ``source``, the file's path) for
    each one ignored, in the file's order."""
    values: dict[str, Value] = {}
    problems: list[str] = []
    for key, value in table.items():
        kind = SETTINGS_KEYS.get(key)
        if kind is None:
            problems.append(
                f"{source} [settings]: unknown key {_shown(key)} ignored (known: {_KNOWN_TEXT})"
            )
        elif kind is bool and not isinstance(value, bool):
            problems.append(
                f"{source} [settings]: {key} = {_shown(value)} ignored: write true or false"
            )
        elif kind is str and not isinstance(value, str):
            problems.append(
                f"{source} [settings]: {key} = {_shown(value)} ignored: write a quoted name"
            )
        elif key == "theme" and themes is not None and value not in themes:
            problems.append(
                f"{source} [settings]: theme = {_shown(value)} is no theme here: ignored "
                "(Ctrl+P, Theme lists them)"
            )
        else:
            values[key] = value  # type: ignore[assignment]  # checked just above
    return values, problems


def _shown(value: object) -> str:
    """A value from the file as it goes into a message: short, control characters escaped."""
    text = toml_value(value) if isinstance(value, str | bool) else repr(value)
    return text if len(text) <= 40 else text[:39] + "…"


def toml_value(value: Value) -> str:
    """``true``, ``false`` or a basic string, escaped as TOML reads it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return toml_string(value)


_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f"}
_ESCAPES["\r"] = "\\r"


def toml_string(text: str) -> str:
    """``"..."``: quotes and backslashes escaped, every control character too."""
    out = []
    for char in text:
        if char in _ESCAPES:
            out.append(_ESCAPES[char])
        elif ord(char) < 0x20 or ord(char) == 0x7F:
            out.append(f"\\u{ord(char):04X}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


def update_settings_text(text: str, values: Mapping[str, Value], source: str) -> str:
    """``text`` (a config file) with ``values`` set in its ``[settings]`` table and
    every other byte kept; InputError (one line, led by ``source``) when the text is not
    valid TOML or cannot be rewritten safely."""
    for key, value in values.items():
        if key not in SETTINGS_KEYS or not isinstance(value, SETTINGS_KEYS[key]):
            raise ValueError(f"not a setting: {key} = {value!r}")  # a bug, not the file's
    before = parse_toml(text, source)
    # Lines end at \n only in TOML; a file whose every line ends \r\n is edited with \n
    # and given its \r\n back, new lines included (tomlkit writes \n).
    windows = "\r\n" in text and text.count("\n") == text.count("\r\n")
    edited = text.replace("\r\n", "\n") if windows else text
    new = _edited(edited, values) if "settings" in before else _appended(edited, values)
    if new is not None and windows:
        new = new.replace("\n", "\r\n")
    old = before.get("settings")
    expected = {**before, "settings": {**(old if isinstance(old, dict) else {}), **values}}
    try:
        after = None if new is None else tomllib.loads(new)
    except (ValueError, RecursionError):  # TOMLDecodeError is a ValueError
        after = None
    if new is None or after != expected:
        raise InputError(
            f"{source}: its [settings] cannot be rewritten safely: write them as a [settings] "
            "table with one key = value a line"
        )
    return new


def _appended(text: str, values: Mapping[str, Value]) -> str:
    """A ``[settings]`` table after the text, a blank line between."""
    import tomlkit

    if text and not text.endswith("\n"):
        text += "\n"
    return text + ("\n" if text else "") + tomlkit.dumps({"settings": dict(values)})


def _edited(text: str, values: Mapping[str, Value]) -> str | None:
    """The text with ``values`` set in its ``settings`` table; None when that is no
    table, or tomlkit cannot edit it."""
    import tomlkit
    from tomlkit.items import InlineTable, Table

    from .tomlkit_compat import append_after_last_key

    try:
        document = tomlkit.parse(text)
        table = document["settings"]
        if not isinstance(table, MutableMapping):  # settings = 3, [[settings]]
            return None
        added = {key: value for key, value in values.items() if key not in table}
        for key, value in values.items():
            if key not in added:
                table[key] = value  # in place: its key, comment and indent kept
        if isinstance(table, Table | InlineTable):
            append_after_last_key(table, added)  # before the comments that follow
        else:  # split across the file: tomlkit finds the place
            table.update(added)
        return document.as_string()
    except Exception:  # whatever tomlkit makes of a file it cannot edit: left alone
        return None
