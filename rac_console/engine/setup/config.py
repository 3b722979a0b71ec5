"""The config file: target profiles (and the console's settings), read with tomllib.

``$RAC_CONSOLE_CONFIG``, or ``config.toml`` in the user's config directory
(platformdirs), or the file a script names (``rac.connect(..., config=PATH)``). No
file at the default place means no profiles; a file a user named must exist. Anything
wrong with one that exists is an InputError of one line naming the file (a TOML syntax
error with its line), never a traceback, so that a broken file cannot silently drop a
profile's read-only guard.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ...commands.cells import CellSpec
from ...commands.config_keys import MQTT_KEYS, Withheld
from ...commands.plant import CA_FILE_ENV, NO_CREDENTIALS, PASSWORD_ENV, USERNAME_ENV, Credentials
from ...commands.policy import TargetProfile
from ...protocol.errors import InputError
from ..files.textfile import read_text_file
from .where import Where, reaches, this_process

CONFIG_ENV = "RAC_CONSOLE_CONFIG"


def config_path() -> Path:
    """Where the config file is: ``$RAC_CONSOLE_CONFIG``, or the user's config directory;
    InputError when the variable names a path that cannot be expanded."""
    named = os.environ.get(CONFIG_ENV)
    if named:
        return named_path(named, CONFIG_ENV)
    from platformdirs import user_config_path

    return user_config_path("rac-console") / "config.toml"


def named_path(named: str | os.PathLike[str], by: str) -> Path:
    """A config file's path as a user named it (``by``: ``RAC_CONSOLE_CONFIG``,
    ``config``), ``~`` expanded as a shell would; InputError when it cannot be."""
    try:
        return Path(named).expanduser()
    except RuntimeError as exc:  # ~user that does not exist, no home directory
        raise InputError(f"{by}={os.fspath(named)}: {exc}") from None


@dataclass(frozen=True)
class Config:
    """The config file as loaded: its profiles by name, and its ``[settings]`` table as
    read (the console's theme, layout and frame-log toggles: see :mod:`.settings`)."""

    path: Path
    found: bool = False  # False: no file there (no profiles)
    profiles: Mapping[str, TargetProfile] = field(default_factory=dict)
    settings: Mapping[str, object] = field(default_factory=dict)
    cells: Mapping[str, CellSpec] = field(default_factory=dict)
    mqtt: Credentials = NO_CREDENTIALS  # the [mqtt] table
    #: The place it was read for, and the keys it held that reach more than that place
    #: may (not read: see :mod:`rac_console.commands.config_keys`).
    where: Where = Where.CONSOLE
    withheld: Withheld = ()

    @property
    def named(self) -> str:
        """The file as a message names it: ``PATH``, or ``PATH (no such file)``."""
        return str(self.path) if self.found else f"{self.path} (no such file)"

    def credentials(self) -> Credentials:
        """Who the console is to an MQTT broker: the environment's
        ``RAC_MQTT_USERNAME``, ``RAC_MQTT_PASSWORD`` and ``RAC_MQTT_CA_FILE`` where set,
        else the config file's ``[mqtt]`` table; neither where the place does not read
        that key (a served console)."""
        env = os.environ

        def given(key: str, variable: str, in_file: str | None) -> str | None:
            return (env.get(variable) or in_file) if reaches(self.where, MQTT_KEYS[key]) else None

        return Credentials(
            given("username", USERNAME_ENV, self.mqtt.username),
            given("password", PASSWORD_ENV, self.mqtt.password),
            given("ca_file", CA_FILE_ENV, self.mqtt.ca_file),
            self.mqtt.keepalive,
        )


def load_config(
    path: Path | None = None, where: Where | None = None, *, named_by: str | None = None
) -> Config:
    """The config file at ``path`` (default: :func:`config_path`) as ``where`` reads it
    (default: this process's place): a key that reaches more than that place may is not
    read at all, only named in ``withheld``. InputError, one line, for anything wrong
    with what is read.

    A file a user named (``$RAC_CONSOLE_CONFIG``, or ``path`` with ``named_by`` saying
    who named it, ``~`` expanded) must exist: read as no file, a typo would quietly drop
    every profile's guard. Only the default place may hold none."""
    if path is None and os.environ.get(CONFIG_ENV):
        named_by = CONFIG_ENV
    if path is None:
        path = config_path()
    elif named_by is not None:
        path = named_path(path, named_by)
    where = this_process() if where is None else where
    try:
        exists = path.exists()
    except (OSError, RuntimeError) as exc:
        raise InputError(f"cannot read {path}: {getattr(exc, 'strerror', None) or exc}") from None
    if not exists and named_by is not None:  # a typo must not quietly drop a read-only profile
        raise InputError(f"{path} (named by {named_by}) does not exist")
    if not exists:
        return Config(path, where=where)
    from ...commands.config_keys import withhold
    from ...commands.profiles import parse_config  # TOML and its checks: for a file there
    from ...commands.tomltext import parse_toml

    text = read_text_file(path, "a config file")
    data, withheld = withhold(parse_toml(text, str(path)), lambda reach: reaches(where, reach))
    parsed = parse_config(data, str(path))
    return Config(
        path, True, parsed.profiles, parsed.settings, parsed.cells, parsed.mqtt, where, withheld
    )
