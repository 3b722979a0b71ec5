"""``rac-console paths``: where the config file and the history live on this machine
(they differ by system: ``%LOCALAPPDATA%\\rac-console\\rac-console\\`` on Windows)."""

from __future__ import annotations

import os

from ..engine.setup.config import CONFIG_ENV, config_path
from ..present.history import default_history_path
from ..protocol import InputError
from ..protocol.text import terminal_safe


def paths() -> int:
    """One line each: what, where, and whether it is there yet."""
    try:
        config = config_path()
    except InputError as exc:
        print(f"rac-console: {terminal_safe(str(exc))}")
        return 2
    named = f" (named by {CONFIG_ENV})" if os.environ.get(CONFIG_ENV) else ""
    for what, path, extra in (
        ("config", config, named),
        ("history", default_history_path(), " (--history FILE names another)"),
    ):
        state = "" if path.exists() else ", not there yet"
        print(f"{what:<8} {terminal_safe(str(path))}{extra}{state}")
    return 0
