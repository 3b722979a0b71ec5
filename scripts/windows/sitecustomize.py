"""Copied by scripts/windows-tests into the Windows CPython's Lib\\site-packages.

Wine 8 lacks the WMI service that CPython 3.13's ``platform`` asks first
(``platform._wmi_query``): the query does not fail but hangs for about 13 s, and every
``platform.system()``/``platform.platform()`` (Textual, pytest's header, hypothesis) pays
for it. On real Windows a failing WMI query raises OSError and ``platform`` falls back
to the registry and ``sys.getwindowsversion()``; make it fail here the same way.
Nothing of rac-console is changed by this.
"""

import platform


def _no_wmi(*args, **kwargs):
    raise OSError("WMI is not available under Wine (scripts/windows/sitecustomize.py)")


platform._wmi_query = _no_wmi
