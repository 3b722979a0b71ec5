"""Snapshot of the frame log's hex view (F7) with the gaps, a slow reply highlighted.

Staged as in test_snapshots.py: nothing polled, frames with fixed times (UTC).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.protocol import parse_response
from rac_console.session import Frame
from tests.support.drivers import make_app, until

pytestmark = pytest.mark.slow

T0 = 1_700_000_000.125
#: (seconds after T0, direction, bytes): a quick exchange, a slow reply (the app's timeout
#: is 1 s: over 0.5 s is slow), a reply with bytes no terminal may see raw, and one long
#: enough that its hex goes under it.
STAGED = [
    (0.0, "tx", b"GET:RC8:10:I:\r"),
    (0.00021, "rx", b"0,3,123\r"),
    (0.2502, "tx", b"GET:RC8:1:S:\r"),
    (0.9012, "rx", b'0,8,"ok"\r'),
    (1.0, "tx", b"GET:RC8:2:S:\r"),
    (1.0004, "rx", b'0,8,"\x1b[2J\x9b"\r'),
    (1.5, "tx", b"GET:RC8:1:P:\r"),
    (1.5003, "rx", b"0,8196,350.5,-12.25,450,180,0,180,5\r"),
]


def test_hex_view_with_gaps(snap_compare, tmp_path: Path, utc: None) -> None:
    app = make_app(tmp_path, timeout=1.0)  # the picture's timeouts say 1 s

    async def run_before(pilot) -> None:
        await until(pilot, lambda: app.main_screen.status is not None, "the first status")
        app.main_screen.panes.command_line.cursor_blink = False
        await pilot.press("f7")
        log = app.main_screen.panes.frame_log
        log.clear()
        sent_at = 0.0
        for offset, direction, data in STAGED:
            rtt, reply = None, None
            if direction == "tx":
                sent_at = offset
            else:
                rtt = offset - sent_at
                if data.isascii():
                    reply = parse_response(data[:-1].decode("ascii"))
            log.add(Frame(T0 + offset, direction, data, rtt, response=reply))  # type: ignore[arg-type]
        app.main_screen.flush_log()
        await until(pilot, lambda: app.main_screen.frames_per_second() == 0, "the rate back to 0")
        app.main_screen.refresh_table()
        await pilot.pause(0.2)

    assert snap_compare(app, terminal_size=(110, 44), run_before=run_before)
