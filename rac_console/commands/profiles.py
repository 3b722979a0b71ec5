"""Target profiles from the config file, parsed: pure (a dict in, profiles out).

The file (read by :mod:`rac_console.engine.setup.config`) names targets::

    [target.cell3]
    host = "192.168.0.1"
    port = 5006                         # optional
    label = "Cell 3 — welding"          # shown on the status line and the border
    colour = "red"                      # or color; a colour name or "#rrggbb"
    writes = "confirm"                  # open | confirm | read-only (default open)
    allow = ["I 100-199", "IO 64-71"]   # optional: the only variables writable
    publish = "mqtt://broker/line2"     # optional: its watched values to the plant

and may hold a ``[settings]`` table, kept as it is for the settings that persist, and an
``[mqtt]`` table: the broker's ``username``, ``password`` and ``ca_file``, which are never
typed on a command line, and ``keepalive`` (seconds between pings to a quiet broker).
Nothing is guessed: every problem is an InputError of one line naming the file, the
profile and the key, and saying how to write it.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from ..protocol import InputError
from ..protocol.text import terminal_safe
from .cells import CellSpec, parse_cells
from .config_keys import MQTT_KEYS, TARGET_KEYS
from .names import case_collision, find_name
from .plant import KEEPALIVE, KEEPALIVE_RANGE, NO_CREDENTIALS, Credentials, publish_setting
from .policy import (
    STRICTNESS,
    AllowRange,
    TargetProfile,
    WritePolicy,
    Writes,
    parse_allow,
    strictest,
)

DEFAULT_PORT = 5006
#: ``connect sim`` and the status line's name for the built-in simulator.
SIMULATOR_NAME = "sim"

_PROFILE_KEYS = tuple(TARGET_KEYS)  # each with its reach, declared there
_KEYS_TEXT = "host, port, label, colour (or color), writes, allow, publish"
_TOP_KEYS = ("target", "settings", "cell", "mqtt")
_MQTT_KEYS = tuple(MQTT_KEYS)
_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_-]*", re.ASCII)
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+", re.ASCII)
_COLOUR_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*", re.ASCII)
_COLOUR_HEX = re.compile(r"#[0-9A-Fa-f]{6}", re.ASCII)
_WRITES_TEXT = '"open", "confirm" or "read-only"'

#: Makes the InputError of a problem, its message led by the file's path.
_Fail = Callable[[str], InputError]


@dataclass(frozen=True)
class ParsedConfig:
    """What the config file holds: its profiles by name, and its ``[settings]`` as read."""

    profiles: dict[str, TargetProfile] = field(default_factory=dict)
    settings: dict[str, object] = field(default_factory=dict)
    cells: dict[str, CellSpec] = field(default_factory=dict)
    mqtt: Credentials = NO_CREDENTIALS


def completion_targets(profiles: Mapping[str, TargetProfile]) -> list[tuple[str, str]]:
    """What ``connect`` completes to besides sim: each profile's name, with its label (or
    its address) as the candidate's help, escaped."""
    return [
        (name, terminal_safe(profile.label or f"{profile.host}:{profile.port}"))
        for name, profile in sorted(profiles.items())
    ]


def colour_syntax_ok(text: str) -> bool:
    """``#rrggbb`` or a name of letters, digits and underscores (``bright_red``,
    ``grey35``). Whether a front end knows the name is its own affair: an unknown one
    falls back to its default colours there."""
    return bool(_COLOUR_HEX.fullmatch(text) or _COLOUR_NAME.fullmatch(text))


def table_name(name: str) -> str:
    """``[target.cell3]``, or ``[target."a b"]`` for a name TOML must quote."""
    if _BARE_KEY.fullmatch(name):
        return f"[target.{name}]"
    return f"[target.{_shown(name).replace(chr(39), chr(34))}]"


def _shown(value: object) -> str:
    """A value from the file as it goes into a message: quoted, control characters escaped."""
    return ascii(value) if isinstance(value, str) and not value.isprintable() else repr(value)


def parse_config(data: Mapping[str, object], source: str) -> ParsedConfig:
    """The profiles and settings of a config file read as ``data``; ``source`` (the
    file's path) begins every message."""

    def fail(text: str) -> InputError:
        return InputError(f"{source}: {text}")

    for key in data:
        if key not in _TOP_KEYS:
            raise fail(
                f"unknown table or key {_shown(key)}: use [target.NAME] tables "
                "(one per target), [cell.NAME] tables, [settings] and [mqtt]"
            )
    settings = data.get("settings", {})
    if not isinstance(settings, dict):
        raise fail("[settings] is a table: write [settings] on a line of its own, then its keys")
    targets = data.get("target", {})
    example = '[target.cell3] then host = "192.168.0.1" on the next line'
    if not isinstance(targets, dict):
        raise fail(f"[target] holds one table per profile: write {example}")
    found: dict[str, TargetProfile] = {}
    for name, table in targets.items():
        if not isinstance(table, dict):
            if name in _PROFILE_KEYS:  # [target] host = ...: no profile name
                raise fail(f"[target] holds one table per profile: write {example}")
            raise fail(
                f"{table_name(name)} is not a table: write {table_name(name)} on a "
                'line of its own, then host = "..." under it'
            )
        found[name] = _profile(name, table, fail)
    if (pair := case_collision(found)) is not None:
        raise fail(
            f"{table_name(pair[0])} and {table_name(pair[1])} differ only in case, and a "
            "name is found in any case (-H, connect, @NAME): rename one of them"
        )
    cells = parse_cells(data.get("cell"), found, fail)
    return ParsedConfig(found, dict(settings), cells, _mqtt(data.get("mqtt", {}), fail))


def _mqtt(table: object, fail: _Fail) -> Credentials:
    """``[mqtt]``: who the console is to the broker, the CA that signs it, and how often
    it pings a quiet broker."""
    if not isinstance(table, dict):
        raise fail('[mqtt] is a table: write [mqtt] on a line of its own, then username = "..."')
    for key, value in table.items():
        if key not in _MQTT_KEYS:
            raise fail(
                f"[mqtt] unknown key {_shown(key)}: use username, password, ca_file and keepalive"
            )
        if key == "keepalive":
            low, high = KEEPALIVE_RANGE
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
                raise fail(
                    f"[mqtt] keepalive: write keepalive = {KEEPALIVE} (seconds, {low} to {high})"
                )
        elif not isinstance(value, str):  # the value is not shown: it may be the password
            raise fail(f'[mqtt] {key}: write {key} = "..." (text in quotes)')
    return Credentials(
        table.get("username"),
        table.get("password"),
        table.get("ca_file"),
        table.get("keepalive", KEEPALIVE),
    )


def _profile(name: str, table: dict[str, object], fail: _Fail) -> TargetProfile:
    where = table_name(name)
    if not _NAME.fullmatch(name):
        raise fail(
            f"profile name {_shown(name)}: use letters, digits, - and _ "
            "(it is typed after -H and connect), e.g. [target.cell3]"
        )
    if name == SIMULATOR_NAME:
        raise fail(
            f"{where}: 'sim' names the built-in simulator (connect sim): choose another name"
        )
    for key in table:
        if key not in _PROFILE_KEYS:
            raise fail(f"{where} unknown key {_shown(key)}: use {_KEYS_TEXT}")
    if "host" not in table:
        raise fail(f'{where} has no host: add host = "192.168.0.1" (the controller\'s address)')
    host = table["host"]
    if not isinstance(host, str) or not host or any(c.isspace() for c in host):
        raise fail(f'{where} host: write host = "192.168.0.1" (an address or a name, no spaces)')
    if not host.isprintable():
        raise fail(f"{where} host {_shown(host)}: an address holds no control characters")
    port = table.get("port", DEFAULT_PORT)
    if isinstance(port, bool) or not isinstance(port, int):
        raise fail(f"{where} port: write port = 5006 (a number, no quotes), got {_shown(port)}")
    if not 0 < port < 65536:
        raise fail(f"{where} port: a port is a number from 1 to 65535, got {port}")
    label = table.get("label")
    if label is not None and not isinstance(label, str):
        raise fail(f'{where} label: write label = "Cell 3 — welding" (text in quotes)')
    return TargetProfile(
        name=name,
        host=host,
        port=port,
        label=label or None,
        colour=_colour(where, table, fail),
        policy=WritePolicy(
            _writes(where, table, fail), _allow(where, table, fail), f"profile {name}"
        ),
        publish=publish_setting(where, table.get("publish"), fail),
    )


def _colour(where: str, table: dict[str, object], fail: _Fail) -> str | None:
    if "colour" in table and "color" in table:
        raise fail(f"{where} has colour and color: keep one")
    key = "color" if "color" in table else "colour"
    colour = table.get(key)
    if colour is None:
        return None
    if not isinstance(colour, str) or not colour_syntax_ok(colour):
        raise fail(
            f'{where} {key} {_shown(colour)}: write a colour name or "#rrggbb", '
            f'e.g. {key} = "red", {key} = "bright_blue" or {key} = "#ff8700"'
        )
    return colour.lower()


def _writes(where: str, table: dict[str, object], fail: _Fail) -> Writes:
    writes = table.get("writes", Writes.OPEN.value)
    for mode in Writes:
        if writes == mode.value:
            return mode
    raise fail(f"{where} writes = {_shown(writes)}: write writes = {_WRITES_TEXT}")


def _allow(where: str, table: dict[str, object], fail: _Fail) -> tuple[AllowRange, ...] | None:
    allow = table.get("allow")
    if allow is None:
        return None
    how = 'write a list, allow = ["I 100-199", "IO 64-71"]'
    if not isinstance(allow, list) or not all(isinstance(item, str) for item in allow):
        raise fail(f"{where} allow: {how}, got {_shown(allow)}")
    ranges = []
    for item in allow:
        try:
            ranges.append(parse_allow(item))
        except InputError as exc:
            raise fail(f"{where} allow: {exc}") from None
    return tuple(ranges)


#: The addresses a host name or address text stands for (an IPv4-mapped IPv6 address as
#: its IPv4 form), or None when it cannot be resolved. Given by the caller: this module
#: is pure, and resolving is a socket affair (see :mod:`rac_console.session.endpoints`).
Addresses = Callable[[str], "frozenset[str] | None"]


@dataclass(frozen=True)
class ProfileMatch:
    """Who a target is: the profile shown for it (its name, label and colour), the
    profiles whose rules apply to it, and the profiles of its port whose host could not
    be resolved (matched by name and text only: said to the user once)."""

    profile: TargetProfile | None
    unresolved: tuple[TargetProfile, ...] = ()
    #: Every profile at the endpoint reached, and the one named if it is elsewhere: the
    #: rules are the strictest of all of them (naming a profile never makes them laxer).
    ruling: tuple[TargetProfile, ...] = ()

    @property
    def policy(self) -> WritePolicy | None:
        """The rules that apply: the strictest of the ruling profiles'; None for none."""
        if not self.ruling:
            return None
        return strictest([profile.policy for profile in self.ruling])

    def notices(self) -> list[str]:
        """One line per profile that could not be matched by its address."""
        return [
            f"profile {p.name}: its host {terminal_safe(p.host)} cannot be resolved, so its "
            f"rules apply only when the target is typed as {p.name} or {terminal_safe(p.host)}"
            for p in self.unresolved
        ]


def find_profile(profiles: Mapping[str, TargetProfile], name: str) -> TargetProfile | None:
    """The profile named ``name`` in any case (names that differ only in case are
    refused when the file is read), or None."""
    found = find_name(profiles, name)
    return profiles[found] if found is not None else None


def match_profile(
    profiles: Mapping[str, TargetProfile],
    name_or_host: str,
    port: int | None = None,
    addresses: Addresses | None = None,
) -> ProfileMatch:
    """The profiles of the endpoint ``name_or_host`` reaches: a profile's name (in any
    case) reaches its host at ``port`` (None: its own port), a host ``port`` (None: the
    default). Hosts are compared as text and, with ``addresses``, as the addresses both
    sides resolve to (``127.1``, ``localhost`` and ``0x7f000001`` are all 127.0.0.1).
    The profile shown is the one named, unless another profile names that endpoint (the
    strictest there is shown); the rules are those of every profile there and of the
    one named."""
    named = find_profile(profiles, name_or_host)
    host = named.host if named is not None else name_or_host
    wanted = (named.port if named is not None else DEFAULT_PORT) if port is None else port
    same, unresolved = _at_endpoint(profiles, host, wanted, addresses)
    if named is not None and named.port == wanted and named not in same:
        same.insert(0, named)
    ruling = [*same, *([named] if named is not None and named not in same else [])]
    shown = (
        named
        if named is not None and (named in same or not same)
        else max(same, key=lambda p: (STRICTNESS[p.policy.writes], p.policy.allow is not None),
                 default=None)
    )  # fmt: skip
    return ProfileMatch(shown, tuple(unresolved), tuple(ruling))


def _at_endpoint(
    profiles: Mapping[str, TargetProfile], host: str, port: int, addresses: Addresses | None
) -> tuple[list[TargetProfile], list[TargetProfile]]:
    """The profiles at ``host:port``, and those of that port whose host cannot be resolved."""
    key = host.casefold()
    at_port = [p for p in profiles.values() if p.port == port]
    same = [p for p in at_port if p.host.casefold() == key]
    unresolved: list[TargetProfile] = []
    others = [p for p in at_port if p.host.casefold() != key]
    typed = addresses(host) if addresses is not None and others else None
    if addresses is not None and typed:  # a host that cannot be resolved reaches nothing
        for profile in others:
            theirs = addresses(profile.host)
            if theirs is None:
                unresolved.append(profile)
            elif theirs & typed:
                same.append(profile)
    return same, unresolved


def could_be_profile_name(host: str) -> bool:
    """A word that could be a misspelt profile (said so when it cannot be reached): no
    dot, no colon, not localhost."""
    return "." not in host and ":" not in host and host.lower() != "localhost"
