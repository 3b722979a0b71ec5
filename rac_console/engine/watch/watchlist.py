"""A cell's watch list as TOML: one ``[[watch]]`` table per row (type, index, label)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from ...commands.language import VarRef
from ...commands.tomltext import parse_toml
from ...protocol import InputError, kind_of, parse_index
from ..files.textfile import read_text_file

#: A watch list larger than this is not a cell's list: refused before it is parsed.
#: Rows a watch list may hold (a console polls every row over one session).
MAX_ROWS = 4096
#: The longest ``every`` a row may ask for, in seconds (as for ``interval``).
MAX_EVERY = 3600


def _toml_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"')
    escaped = "".join(ch if ch >= " " and ch != "\x7f" else f"\\u{ord(ch):04x}" for ch in escaped)
    return f'"{escaped}"'


#: One row of a watch list: the variable, its label, its own poll period (or None).
Row = tuple[VarRef, str, float | None]

_KEYS = ("type", "index", "label", "every")


def dumps(rows: Iterable[Row]) -> str:
    parts = ["# rac-console watch list\n"]
    for var, label, every in rows:
        parts.append(f'\n[[watch]]\ntype = "{var.kind.code}"\nindex = {var.index}\n')
        if label:
            parts.append(f"label = {_toml_string(label)}\n")
        if every is not None:
            parts.append(f"every = {every!r}\n")
    return "".join(parts)


def loads(text: str) -> list[Row]:
    """Rows of a watch list; InputError naming the first bad entry (nothing is guessed:
    an unknown key, an index written as text or a row written twice is refused)."""
    data = parse_toml(text, "the watch list")
    entries = data.get("watch", [])
    if isinstance(entries, dict):
        entries = [entries]
    if not isinstance(entries, list):
        raise InputError("a watch list holds [[watch]] tables with type, index and label")
    if len(entries) > MAX_ROWS:
        raise InputError(f"a watch list holds at most {MAX_ROWS} rows; this one has more than that")
    rows: list[Row] = []
    first_entry: dict[VarRef, int] = {}
    for n, entry in enumerate(entries, 1):
        row = _row(n, entry)
        if row[0] in first_entry:
            raise InputError(f"watch entry {n} repeats {row[0]} (entry {first_entry[row[0]]})")
        first_entry[row[0]] = n
        rows.append(row)
    return rows


def _row(n: int, entry: object) -> Row:
    if not isinstance(entry, dict):
        raise InputError(f"watch entry {n} is not a table")
    unknown = [key for key in entry if key not in _KEYS]
    if unknown:
        raise InputError(
            f"watch entry {n} has an unknown key {unknown[0]!r}: use {', '.join(_KEYS)}"
        )
    for key in ("type", "index"):
        if key not in entry:
            raise InputError(f"watch entry {n} has no {key!r}")
    index, label, every = entry["index"], entry.get("label", ""), entry.get("every")
    if isinstance(index, bool) or not isinstance(index, int):
        raise InputError(f"watch entry {n}: index is a whole number (index = 10), got {index!r}")
    if not isinstance(label, str):
        raise InputError(f"watch entry {n}: label is text in quotes, got {label!r}")
    if every is not None and (
        isinstance(every, bool) or not isinstance(every, int | float) or not 0 <= every <= MAX_EVERY
    ):
        raise InputError(f"watch entry {n}: every is 0 to {MAX_EVERY} seconds, got {every!r}")
    try:
        var = VarRef(kind_of(str(entry["type"])), parse_index(str(index)))
    except InputError as exc:
        raise InputError(f"watch entry {n}: {exc}") from None
    return var, label, None if every is None else float(every)


def save(path: str | Path, rows: Iterable[Row]) -> None:
    try:
        Path(path).expanduser().write_text(dumps(rows), encoding="utf-8")
    except (OSError, RuntimeError) as exc:
        raise InputError(f"cannot write {path}: {getattr(exc, 'strerror', None) or exc}") from None


def load(path: str | Path) -> list[Row]:
    """The rows of a watch list file; InputError, one line, for anything wrong with it."""
    text = read_text_file(Path(path).expanduser(), "a watch list", path)
    return loads(text)
