"""A PyInstaller runtime hook of rac-console.exe (scripts/windows-zip): under Wine only.

Wine 8 lacks what CPython 3.13's ``platform`` asks WMI first (``platform._wmi_query``):
under Wine the query calls an unimplemented ``propsys.dll`` function and the process
aborts (prometheus-client asks ``platform`` at import, so ``--metrics`` died). On real
Windows a failing WMI query raises OSError and ``platform`` falls back to the registry;
under Wine it is made to fail that way (as scripts/windows/sitecustomize.py does for the
test lane). On Windows itself nothing is changed.
"""

import sys


def _under_wine() -> bool:
    try:
        import ctypes

        return hasattr(ctypes.WinDLL("ntdll"), "wine_get_version")
    except (AttributeError, OSError):
        return False


def _no_wmi(*args: object, **kwargs: object) -> object:
    raise OSError("WMI is not available under Wine")


if sys.platform == "win32" and _under_wine():
    import platform

    platform._wmi_query = _no_wmi  # type: ignore[attr-defined]
