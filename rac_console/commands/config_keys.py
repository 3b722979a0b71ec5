"""Every key the config file may hold, by table, with what it reaches besides the
controller it names (as a command's spec declares it: :class:`~.routing.Traits`).

The parsers take their lists of known keys from here (:mod:`.profiles`,
:mod:`.cells`), so a key cannot be added without its reach. A place that may not reach
the network or the files (a console served to a browser) gets the file without the keys
that would (:func:`withhold`) before anything reads it, and says which once
(:func:`withheld_notice`). ``[settings]`` is the console's look and reaches nothing; a
served console neither reads nor writes it for another reason (writing it back writes
this file: see :mod:`rac_console.tui.app`). Pure.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping

from .reach import Reach

#: ``[target.NAME]``: a controller. Its host and port are the target itself.
TARGET_KEYS: dict[str, Reach] = {
    "host": Reach.TARGET,
    "port": Reach.TARGET,
    "label": Reach.TARGET,
    "colour": Reach.TARGET,
    "color": Reach.TARGET,
    "writes": Reach.TARGET,
    "allow": Reach.TARGET,
    "publish": Reach.NETWORK,  # a broker: another host
}
#: ``[cell.NAME]``: targets opened together.
CELL_KEYS: dict[str, Reach] = {
    "targets": Reach.TARGET,
    "watch": Reach.TARGET,
    "publish": Reach.NETWORK,
}
#: ``[mqtt]``: who the console is to a broker. Only publishing uses it (another host);
#: ``ca_file`` is read from this machine's files.
MQTT_KEYS: dict[str, Reach] = {
    "username": Reach.NETWORK,
    "password": Reach.NETWORK,
    "ca_file": Reach.FILES,
    "keepalive": Reach.NETWORK,
}
#: The tables of named tables (``[target.NAME]``) and the plain tables (``[mqtt]``).
NAMED_TABLES: dict[str, dict[str, Reach]] = {"target": TARGET_KEYS, "cell": CELL_KEYS}
PLAIN_TABLES: dict[str, dict[str, Reach]] = {"mqtt": MQTT_KEYS}

#: A key the place does not read: the table as the file names it, and the key.
Withheld = tuple[tuple[str, str], ...]
#: How many tables the notice names; the rest are counted.
MOST_NAMED = 4

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+", re.ASCII)


def withhold(
    data: Mapping[str, object], reads: Callable[[Reach], bool]
) -> tuple[dict[str, object], Withheld]:
    """``data`` (the config file as TOML read it) without the keys of known tables whose
    reach ``reads`` refuses, and those keys in the file's order. Anything else is left
    as it is, for the parsers to judge as everywhere."""
    kept = dict(data)
    withheld: list[tuple[str, str]] = []
    for table, entries in data.items():
        if table in NAMED_TABLES and isinstance(entries, dict):
            named: dict[str, object] = {}
            for name, entry in entries.items():
                label = f"[{table}.{_key(name)}]"
                named[name] = _without(entry, NAMED_TABLES[table], reads, label, withheld)
            kept[table] = named
        elif table in PLAIN_TABLES:
            kept[table] = _without(entries, PLAIN_TABLES[table], reads, f"[{table}]", withheld)
    return kept, tuple(withheld)


def _without(
    entry: object,
    keys: Mapping[str, Reach],
    reads: Callable[[Reach], bool],
    label: str,
    withheld: list[tuple[str, str]],
) -> object:
    if not isinstance(entry, dict):
        return entry
    gone = [key for key in entry if key in keys and not reads(keys[key])]
    withheld += [(label, key) for key in gone]
    return {key: value for key, value in entry.items() if key not in gone}


def _key(name: object) -> str:
    """A table's name as TOML writes it (quoted unless bare), escaped."""
    text = str(name)
    return text if _BARE_KEY.fullmatch(text) else ascii(text).replace("'", '"')


def withheld_notice(withheld: Withheld) -> str | None:
    """One line saying which settings a served console did not read; None for none."""
    if not withheld:
        return None
    tables: dict[str, list[str]] = {}
    for label, key in withheld:
        tables.setdefault(label, []).append(key)
    named = [f"{label} {', '.join(keys)}" for label, keys in tables.items()]
    if len(named) > MOST_NAMED:
        named[MOST_NAMED:] = [f"{len(named) - MOST_NAMED} more tables"]
    return (
        "not read in a served console, which reaches its controller and nothing else: "
        f"the config file's {'; '.join(named)}"
    )
