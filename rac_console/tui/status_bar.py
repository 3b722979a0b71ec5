"""The status line widget; its text is made in :mod:`rac_console.present.status`."""

from __future__ import annotations

from textual.widgets import Static


class StatusBar(Static):
    pass
