"""What the agent and its clients need to know of a line without running it."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..commands.language import Command
    from ..engine.commands.registry import Registry


def may_write(registry: Registry, what: Command | str) -> bool:
    """Whether a line (or a command) may write, by its command's declared traits; a
    line that does not parse writes nothing (its engine answers it with why)."""
    try:
        command = registry.parse(what) if isinstance(what, str) else what
    except Exception:  # InputError, or a line too long: refused where it runs
        return False
    if command is None:
        return False
    try:
        return bool(registry.traits(command).writes_with(command))
    except LookupError:
        return False
