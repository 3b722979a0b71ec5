"""The built-in commands, each declared once with its handler (see :mod:`..registry`).

Every module here exports ``SPECS``, the entries of its commands (a module groups the
commands that share their words or their parts). ``help`` lists them in the order of
the language's :data:`~rac_console.commands.language.COMMAND_WORDS`. Adding a command
is its entry, in a module of its own or beside its kin (a module is found by being
here), and its word there; an entry without its word, or a word without its entry,
stops the registry from loading (:func:`~..registry.in_order`). At run time,
:meth:`~..registry.Registry.register` adds one more.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Sequence
from types import ModuleType

from ....commands.language import COMMAND_WORDS
from ..registry import AnySpec, Registry, in_order


def modules() -> list[ModuleType]:
    """Every module of this package, by name (a frozen build collects them all:
    ``--collect-submodules rac_console.engine.commands.builtin``)."""
    names = sorted(info.name for info in pkgutil.iter_modules(__path__))
    return [importlib.import_module(f"{__name__}.{name}") for name in names]


def declared() -> list[AnySpec]:
    """Every entry the modules declare, module by module."""
    found: list[AnySpec] = []
    for module in modules():
        specs: Sequence[AnySpec] = module.SPECS
        found.extend(specs)
    return found


#: In the order ``help`` lists them.
BUILTIN = Registry(in_order(declared(), COMMAND_WORDS))

__all__ = ["BUILTIN"]

#: One line of the command language (None for a blank line or a comment).
parse_command = BUILTIN.parse
#: The text of ``help`` or ``help COMMAND``.
help_lines = BUILTIN.help_lines

__all__ += ["help_lines", "parse_command"]
