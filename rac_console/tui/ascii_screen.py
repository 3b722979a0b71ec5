"""The console in ASCII, for Windows' old console host and its fonts: every glyph and
box-drawing character leaves as one ASCII character of the same width, at the last step
(the driver's write), so the layout is the one drawn."""

from __future__ import annotations

from textual.driver import Driver

from ..present.glyphs import SCREEN_TABLE


def ascii_driver(base: type[Driver]) -> type[Driver]:
    """``base`` (the driver Textual picked for this system) writing ASCII."""

    class AsciiDriver(base):  # type: ignore[valid-type, misc]
        def write(self, data: str) -> None:
            super().write(data.translate(SCREEN_TABLE))

    return AsciiDriver
