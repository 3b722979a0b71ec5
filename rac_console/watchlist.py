"""A cell's watch list as TOML: one ``[[watch]]`` table per row (type, index, label)."""

from __future__ import annotations

import tomllib
from collections.abc import Iterable
from pathlib import Path

from .commands.language import VarRef
from .protocol import InputError, kind_of, parse_index

#: A watch list larger than this is not a cell's list: refused before it is parsed.
MAX_FILE_BYTES = 1024 * 1024
#: Rows a watch list may hold (a console polls every row over one session).
MAX_ROWS = 4096


def _toml_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"')
    escaped = "".join(ch if ch >= " " and ch != "\x7f" else f"\\u{ord(ch):04x}" for ch in escaped)
    return f'"{escaped}"'


def dumps(rows: Iterable[tuple[VarRef, str]]) -> str:
    parts = ["# rac-console watch list\n"]
    for var, label in rows:
        parts.append(f'\n[[watch]]\ntype = "{var.kind.code}"\nindex = {var.index}\n')
        if label:
            parts.append(f"label = {_toml_string(label)}\n")
    return "".join(parts)


def loads(text: str) -> list[tuple[VarRef, str]]:
    """Rows of a watch list; InputError naming the first bad entry."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not a TOML watch list: {exc}") from None
    except RecursionError:
        raise InputError("not a watch list: its TOML is nested too deeply") from None
    entries = data.get("watch", [])
    if isinstance(entries, dict):
        entries = [entries]
    if not isinstance(entries, list):
        raise InputError("a watch list holds [[watch]] tables with type, index and label")
    if len(entries) > MAX_ROWS:
        raise InputError(f"a watch list holds at most {MAX_ROWS} rows; this one has more than that")
    rows = []
    for n, entry in enumerate(entries, 1):
        if not isinstance(entry, dict):
            raise InputError(f"watch entry {n} is not a table")
        try:
            kind = kind_of(str(entry["type"]))
            index = parse_index(str(entry["index"]))
        except KeyError as exc:
            raise InputError(f"watch entry {n} has no {exc.args[0]!r}") from None
        except InputError as exc:
            raise InputError(f"watch entry {n}: {exc}") from None
        rows.append((VarRef(kind, index), str(entry.get("label", ""))))
    return rows


def save(path: str | Path, rows: Iterable[tuple[VarRef, str]]) -> None:
    try:
        Path(path).expanduser().write_text(dumps(rows), encoding="utf-8")
    except (OSError, RuntimeError) as exc:
        raise InputError(f"cannot write {path}: {getattr(exc, 'strerror', None) or exc}") from None


def load(path: str | Path) -> list[tuple[VarRef, str]]:
    """The rows of a watch list file; InputError, one line, for anything wrong with it."""
    try:
        file = Path(path).expanduser()
        if file.exists() and not file.is_file():  # a device or a pipe: endless, or no end
            raise InputError(f"{path} is not a regular file: not a watch list")
        with file.open("rb") as handle:
            data = handle.read(MAX_FILE_BYTES + 1)
        if len(data) > MAX_FILE_BYTES:
            raise InputError(
                f"{path} is larger than {MAX_FILE_BYTES // 1024} KiB: not a watch list"
            )
        text = data.decode("utf-8")
    except (OSError, RuntimeError) as exc:
        raise InputError(f"cannot read {path}: {getattr(exc, 'strerror', None) or exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"{path} is not a UTF-8 text file") from None
    return loads(text)
