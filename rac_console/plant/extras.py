"""The optional libraries, imported when asked for, with a message saying how to get
them when they are missing."""

from __future__ import annotations

import importlib
from types import ModuleType

from ..protocol import InputError

#: The extra that brings each library: pip install "rac-console[mqtt]".
_EXTRAS = {
    "paho.mqtt.client": ("mqtt", "paho-mqtt"),
    "prometheus_client": ("metrics", "prometheus-client"),
    "asyncua": ("opcua", "asyncua"),
}


def need(module: str, what: str) -> ModuleType:
    """The module, or InputError: ``what`` needs the extra that brings it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        extra, package = _EXTRAS[module]
        raise InputError(
            f'{what} needs {package}: pip install "rac-console[{extra}]" '
            f"(or pip install {package}) in the environment rac-console runs from"
        ) from None
