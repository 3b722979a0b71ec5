"""A cell: several controllers opened together, one session and one engine each.

Named once in the config file::

    [cell.line2]
    targets = ["cell3", "cell4"]                 # profile names, two to six
    watch = ["cell3 IO 128 part placed",          # optional: TARGET TYPE INDEX [label]
             "cell4 IO 64 go"]

or ad hoc: ``-H cell3,cell4`` (profile names or addresses). A line that starts with
``@NAME `` runs on that target; the others run on the current one (``use NAME``).
Pure: text in, names and lines out.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from ..protocol import InputError
from ..protocol.text import terminal_safe
from .config_keys import CELL_KEYS
from .names import case_collision, find_name

#: A cell holds at most this many targets (a robot cell has two to six controllers).
MOST_TARGETS = 8
#: A cell's ``watch`` list holds at most this many lines: as many rows as a watch file.
MOST_WATCHED = 4096
#: ``--cell demo`` with no [cell.demo] in the config: simulators playing a handshake.
DEMO_CELL = "demo"
_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.:-]*", re.ASCII)
_CELL_KEYS = tuple(CELL_KEYS)  # each with its reach, declared there


@dataclass(frozen=True)
class CellSpec:
    """A ``[cell.NAME]`` table: its targets (profile names) and its watch lines."""

    name: str
    targets: tuple[str, ...]
    watch: tuple[str, ...] = ()
    publish: str | None = None  # mqtt://HOST/PREFIX: every target's values to the plant


def split_hosts(text: str | None) -> list[str] | None:
    """``-H cell3,cell4``: the names, in order; None for one name (a single target,
    exactly as before). InputError for an empty name or one named twice."""
    if text is None or "," not in text:
        return None
    names = [name.strip() for name in text.split(",")]
    if any(not name for name in names):
        raise InputError(
            f"-H {terminal_safe(text)}: a name is missing between commas; write -H cell3,cell4"
        )
    _no_repeats(names, "-H")
    if len(names) > MOST_TARGETS:
        raise InputError(f"-H names {len(names)} targets; a cell holds at most {MOST_TARGETS}")
    return names


def _no_repeats(names: Sequence[str], where: str) -> None:
    seen: set[str] = set()
    for name in names:
        if name.casefold() in seen:
            raise InputError(
                f"{where} names {terminal_safe(name)} twice: one session per controller"
            )
        seen.add(name.casefold())


def split_address(line: str) -> tuple[str | None, str]:
    """``@cell4 get I 10`` -> ``("cell4", "get I 10")``; a line without ``@`` -> (None,
    line). InputError when the name or the command after it is missing."""
    stripped = line.lstrip()
    if not stripped.startswith("@"):
        return None, line
    name, _, rest = stripped[1:].partition(" ")
    if not name:
        raise InputError("@ needs a target's name right after it: @cell4 get I 10")
    if not rest.strip():
        raise InputError(
            f"@{terminal_safe(name)} needs a command after it: @{terminal_safe(name)} get I 10"
        )
    return name, rest.strip()


def not_open(name: str, names: Sequence[str]) -> InputError:
    """What is said of a name that is none of the open targets ``names``: which are."""
    return InputError(
        f"no target named {terminal_safe(name)} is open here; open: {', '.join(names)}"
    )


def _watch_line(
    line: str, targets: Sequence[str], where: str, fail: Callable[[str], InputError]
) -> str:
    """A cell's watch line, led by its target's own name (``CELL3 IO 1`` is ``cell3 IO 1``)."""
    first, _, rest = line.strip().partition(" ")
    found = find_name(targets, first) if first else None
    if found is None:
        raise fail(
            f"{where} watch {terminal_safe(line)!r}: start with one of its targets "
            f'({", ".join(targets)}), e.g. "{targets[0]} IO 128 part placed"'
        )
    return f"{found} {rest.strip()}"


def parse_cells(
    data: object, profiles: Mapping[str, object], fail: Callable[[str], InputError]
) -> dict[str, CellSpec]:
    """The ``[cell.NAME]`` tables of a config file; ``fail`` makes a problem's error."""
    if data is None:
        return {}
    example = '[cell.line2] then targets = ["cell3", "cell4"] on the next line'
    if not isinstance(data, dict):
        raise fail(f"[cell] holds one table per cell: write {example}")
    if (pair := case_collision(data)) is not None:
        raise fail(
            f"[cell.{pair[0]}] and [cell.{pair[1]}] differ only in case, and a name is "
            "found in any case (--cell): rename one of them"
        )
    cells: dict[str, CellSpec] = {}
    for name, table in data.items():
        where = f"[cell.{name}]" if _NAME.fullmatch(str(name)) else f"[cell.{name!r}]"
        if not isinstance(table, dict):
            raise fail(f"{where} is not a table: write {example}")
        if not _NAME.fullmatch(name):
            raise fail(f"cell name {name!r}: use letters, digits, - and _, e.g. [cell.line2]")
        for key in table:
            if key not in _CELL_KEYS:
                raise fail(f"{where} unknown key {key!r}: use targets, watch and publish")
        targets = table.get("targets")
        if not isinstance(targets, list) or not all(isinstance(t, str) for t in targets):
            raise fail(f'{where} targets: write targets = ["cell3", "cell4"] (profile names)')
        targets = list(targets)
        if not targets:
            raise fail(f'{where} targets is empty: name its profiles, targets = ["cell3", "cell4"]')
        if len(targets) > MOST_TARGETS:
            raise fail(f"{where} names {len(targets)} targets; a cell holds at most {MOST_TARGETS}")
        try:
            _no_repeats(targets, where)
        except InputError as exc:
            raise fail(str(exc)) from None
        for n, target in enumerate(targets):
            found = find_name(profiles, target)
            if found is None:
                known = ", ".join(sorted(profiles)) or "none yet"
                raise fail(
                    f"{where} targets: no profile named {terminal_safe(target)} "
                    f"(a [target.NAME] table; profiles: {known})"
                )
            targets[n] = found  # the profile's own name, whatever case it was typed in
        watch = table.get("watch", [])
        if not isinstance(watch, list) or not all(isinstance(w, str) for w in watch):
            raise fail(f'{where} watch: write watch = ["cell3 IO 128 part placed"]')
        if len(watch) > MOST_WATCHED:
            raise fail(
                f"{where} watch holds {len(watch)} lines; a cell watches at most "
                f"{MOST_WATCHED} (as a watch file): keep the ones worth a row"
            )
        watch = [_watch_line(line, targets, where, fail) for line in watch]
        from .plant import publish_setting

        publish = publish_setting(where, table.get("publish"), fail)
        cells[name] = CellSpec(name, tuple(targets), tuple(watch), publish)
    return cells
