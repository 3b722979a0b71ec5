"""TOML text from a file a user wrote (the config file, a watch list), parsed: every
problem one line naming the file, never a traceback. Pure."""

from __future__ import annotations

import tomllib
from typing import Any

from ..protocol import InputError


def parse_toml(text: str, source: str) -> dict[str, Any]:
    """The table ``text`` holds; InputError ``"{source}: not valid TOML: ..."``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:  # "... (at line 3, column 8)"
        raise InputError(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:
        raise InputError(f"{source}: not valid TOML: nested too deeply") from None
    except ValueError as exc:  # an integer of thousands of digits, say
        raise InputError(f"{source}: not valid TOML: {exc}") from None
