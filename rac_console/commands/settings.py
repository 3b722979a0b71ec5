"""The config file's ``[settings]`` table: read, and rewritten in the file's text. Pure.

The console keeps its look there (read by :mod:`rac_console.engine.settings`)::

    [settings]
    theme = "textual-light"   # Ctrl+P, Theme
    io_grid = true            # F5: the I/O grid shown
    poll_frames = false       # F3: poll frames in the log
    hex_view = true           # F7: each frame's bytes in hex
    frame_gaps = true         # t in the log: the time since the previous frame

The file is the user's: :func:`update_settings_text` rewrites only the lines of the
``[settings]`` table (a known key's line in place, keeping its comment; a new key after
the table's last key; the table appended at the end when there is none) and keeps every
other byte. Unknown keys are kept. The result is parsed again and must hold what the
file held with only those settings changed: anything it cannot rewrite safely (a
``settings = {...}`` inline table, dotted ``settings.theme`` keys, a value over several
lines) is an InputError of one line, and the file is left as it is.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Collection, Iterator, Mapping

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

_HEADER = re.compile(r"\s*\[")
_SETTINGS_HEADER = re.compile(r"""\s*\[\s*(?:settings|"settings"|'settings')\s*\]\s*(?:#.*)?""")
#: A value on one line whose end is plain to see: a string, a boolean, a number.
_SIMPLE_VALUE = r"""(?:"(?:[^"\\]|\\.)*"|'[^']*'|true|false|[-+0-9A-Za-z_.:]+)"""
_LINE_END = re.compile(r"\r?\n\Z")
_LINES = re.compile(r"[^\n]*\n|[^\n]+")


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
    lines = _LINES.findall(text)  # at \n only: TOML ends lines nowhere else
    newline = "\r\n" if lines and lines[0].endswith("\r\n") else "\n"
    starts = list(_line_states(lines))  # (clean at its start, a table header)
    header = next(
        (
            n
            for n, (clean, _) in enumerate(starts)
            if clean and _SETTINGS_HEADER.fullmatch(_LINE_END.sub("", lines[n]))
        ),
        None,
    )
    if header is None:
        added = "".join(f"{key} = {toml_value(value)}{newline}" for key, value in values.items())
        head = text
        if head and not head.endswith("\n"):
            head += newline
        new = head + (newline if head else "") + f"[settings]{newline}" + added
    else:
        end = next(
            (n for n in range(header + 1, len(lines)) if starts[n][1]),
            len(lines),
        )
        block = _rewrite_block(lines, starts, header, end, values, newline)
        new = "".join(lines[:header] + block + lines[end:])
    expected = dict(before)
    old_settings = before.get("settings", {})
    expected["settings"] = {**(old_settings if isinstance(old_settings, dict) else {}), **values}
    try:
        after = tomllib.loads(new)
    except (ValueError, RecursionError):  # TOMLDecodeError is a ValueError
        after = None
    if after != expected:
        raise InputError(
            f"{source}: its [settings] cannot be rewritten safely: write them as a [settings] "
            "table with one key = value a line"
        )
    return new


def _rewrite_block(
    lines: list[str],
    starts: list[tuple[bool, bool]],
    header: int,
    end: int,
    values: Mapping[str, Value],
    newline: str,
) -> list[str]:
    """The ``[settings]`` table's lines (its header included), the values set."""
    block = [lines[header]]
    if not block[0].endswith("\n"):
        block[0] += newline
    last_key = 0  # in block: the header, or the last line of the last key = value
    done: set[str] = set()
    n = header + 1
    while n < end:
        # A line and those its value goes on over (up to the next that starts clean).
        stop = next((m for m in range(n + 1, end) if starts[m][0]), end)
        statement = lines[n:stop]
        stripped = lines[n].strip()
        n = stop
        if not stripped or stripped.startswith("#"):
            block.extend(statement)
            continue
        key = _key_of(statement[0])
        if key is not None and key in values and key not in done:
            done.add(key)
            block.append(_replaced(statement, key, values[key], newline))
        else:
            block.extend(statement)
        last_key = len(block) - 1
    added = [f"{key} = {toml_value(v)}{newline}" for key, v in values.items() if key not in done]
    if added and not block[last_key].endswith("\n"):
        block[last_key] += newline
    return block[: last_key + 1] + added + block[last_key + 1 :]


def _key_of(line: str) -> str | None:
    match = re.match(r"""\s*(?:([A-Za-z0-9_-]+)|"([^"\\]*)"|'([^']*)')\s*=""", line)
    if match is None:
        return None
    return next(group for group in match.groups() if group is not None)


def _replaced(statement: list[str], key: str, value: Value, newline: str) -> str:
    """The key's line with the new value: its indent, key spelling and comment kept
    when the old value was on one line; ``key = value`` for one over several lines."""
    ending = _LINE_END.search(statement[-1])
    end = ending.group() if ending else newline
    match = re.match(rf"(\s*[^=]*?\s*=\s*){_SIMPLE_VALUE}(\s*#.*)?\r?\n?\Z", statement[0])
    if len(statement) > 1 or match is None:
        return f"{key} = {toml_value(value)}{end}"
    return f"{match.group(1)}{toml_value(value)}{match.group(2) or ''}{end}"


def _line_states(lines: list[str]) -> Iterator[tuple[bool, bool]]:
    """For each line: whether it starts outside any string or bracket (a key or a
    table header can start there), and whether it is a table header."""
    state = _Scanner()
    for line in lines:
        clean = state.clean
        is_header = clean and _HEADER.match(line) is not None
        if not is_header:
            state.feed(line)
        yield clean, is_header


class _Scanner:
    """Just enough TOML to know where strings, arrays and inline tables end."""

    def __init__(self) -> None:
        self.quote = ""  # the open multi-line string's quotes (\"\"\" or '''), if any
        self.depth = 0  # open [ and {

    @property
    def clean(self) -> bool:
        return not self.quote and self.depth == 0

    def feed(self, line: str) -> None:
        i, size = 0, len(line)
        while i < size:
            if self.quote:
                i = self._in_multiline(line, i)
                continue
            char = line[i]
            if char == "#":
                return
            if line.startswith('"""', i) or line.startswith("'''", i):
                self.quote = line[i : i + 3]
                i += 3
            elif char == '"':
                i = _string_end(line, i + 1, escapes=True)
            elif char == "'":
                i = _string_end(line, i + 1, escapes=False)
            else:
                if char in "[{":
                    self.depth += 1
                elif char in "]}":
                    self.depth = max(0, self.depth - 1)
                i += 1

    def _in_multiline(self, line: str, i: int) -> int:
        if self.quote == '"""' and line[i] == "\\":
            return i + 2
        if line.startswith(self.quote, i):
            i += 3
            extra = 0
            while extra < 2 and i < len(line) and line[i] == self.quote[0]:
                i += 1  # up to two more quotes belong to the string
                extra += 1
            self.quote = ""
            return i
        return i + 1


def _string_end(line: str, i: int, *, escapes: bool) -> int:
    """Past the closing quote of a one-line string opened just before ``i``."""
    quote = line[i - 1]
    while i < len(line):
        if escapes and line[i] == "\\":
            i += 2
        elif line[i] == quote:
            return i + 1
        else:
            i += 1
    return i
