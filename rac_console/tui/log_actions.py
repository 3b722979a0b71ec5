"""The frame log's keys, run by the app (its bindings are ``app.`` actions)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..engine.feedback import Message

if TYPE_CHECKING:
    from .host import ConsoleHost


class LogActions:
    """The frame log's keys, on the app: hex view (F7), frame times (``t``), filter (``/``)."""

    def action_toggle_hex(self: ConsoleHost) -> None:
        log = self.frame_log
        log.hex_view = not log.hex_view
        where = {
            "beside": "beside its text, in one column",
            "under": "on lines under its text (wider terminals put them beside)",
            "mixed": "beside its text, or under it when the line is too long",
            "none": "beside its text, or under it when both do not fit",
        }[log.hex_placement]
        self.show(
            Message(
                f"hex view: each frame's bytes {where} (F7 hides them)"
                if log.hex_view
                else "hex view off"
            )
        )

    def action_toggle_frame_times(self: ConsoleHost) -> None:
        log = self.frame_log
        log.show_gaps = not log.show_gaps
        self.show(
            Message(
                "frame times: the time since the previous frame on each line"
                if log.show_gaps
                else "frame times hidden (t in the frame log shows them)"
            )
        )

    def action_filter_frames(self: ConsoleHost) -> None:
        """``/`` in the frame log: its filter line, with the filter as it is."""
        self.mount_hidden_panes()
        self.log_filter.open()
