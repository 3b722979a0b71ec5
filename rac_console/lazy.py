"""A package's names, imported from its modules when first used (PEP 562).

``from rac_console.protocol.errors import InputError`` runs the package's
``__init__`` first; when that imports every module of the package, the console's
first paint pays for all of them. A package whose ``__init__`` only says where each
name lives (and imports them for the type checker alone) costs nothing until a name
is used, and then only the module that holds it.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from importlib import import_module
from typing import Any


def exports(package: str, where: Mapping[str, str]) -> Callable[[str], Any]:
    """The ``__getattr__`` of ``package``: each name in ``where`` from its module
    (relative to the package, ``".errors"``), kept once asked for."""

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(module, package), name)
        setattr(sys.modules[package], name, value)  # a plain attribute from now on
        return value

    return __getattr__
