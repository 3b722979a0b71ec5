"""Files that may hold values from a production cell are private; the simulator stays local."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from rac_console.present.history import History
from rac_console.protocol import Variant, kind_of
from rac_console.sim.server import is_loopback


def mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


POSIX_MODES = pytest.mark.skipif(
    sys.platform == "win32",
    reason="POSIX file modes: Windows has none; the README says what owner-only means there",
)


def test_record_file_is_owner_only_and_holds_every_frame(tmp_path: Path) -> None:
    record = tmp_path / "frames.jsonl"
    old_umask = os.umask(0o022)
    try:
        result = subprocess.run(
            [sys.executable, "-m", "rac_console", "--record", str(record), "run", "-"],
            input="get I 1\nsend PUT:RC8:10:11,0\n",
            capture_output=True,
            text=True,
            timeout=30,
        )
    finally:
        os.umask(old_umask)
    assert result.returncode == 1
    if sys.platform != "win32":  # POSIX modes; Windows has none (see the README)
        assert mode(record) == 0o600
    frames = [json.loads(line) for line in record.read_text(encoding="utf-8").splitlines()]
    assert [(f["dir"], f["text"]) for f in frames] == [
        ("tx", "GET:RC8:1:I:"),
        ("rx", "0,3,1"),
        ("tx", "PUT:RC8:10:11,0"),
        ("rx", "-2147418107"),
    ]
    assert all("t" in f for f in frames)
    assert "rtt_ms" in frames[1] and "rtt_ms" not in frames[0]


@POSIX_MODES
def test_history_file_is_owner_only(tmp_path: Path) -> None:
    path = tmp_path / "state" / "history"
    History(path).append("put I 1 5")
    assert mode(path) == 0o600


def test_history_file_is_made_in_a_new_folder_on_every_system(tmp_path: Path) -> None:
    """The counterpart where modes mean nothing: the file and its folder are made."""
    path = tmp_path / "state" / "deeper" / "history"
    History(path).append("put I 1 5")
    assert path.read_text(encoding="utf-8").splitlines() == ["put I 1 5"]


@pytest.mark.parametrize(
    "host, local",
    [
        ("127.0.0.1", True),
        ("127.3.2.1", True),
        ("::1", True),
        ("localhost", True),
        ("0.0.0.0", False),
        ("192.168.0.10", False),
        ("controller.example", False),
    ],
)
def test_only_loopback_counts_as_local(host: str, local: bool) -> None:
    assert is_loopback(host) is local


def test_read_only_refuses_puts_in_every_front_end(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "--read-only", "--json", "repl"],
        input="put I 1 5\nPUT:RC8:1:I:3,5\nsend put:RC8:1:I:3,5\nget I 1\n",
        capture_output=True,
        text=True,
        timeout=30,
    )
    objects = [json.loads(line) for line in result.stdout.splitlines()]
    assert [o["ok"] for o in objects] == [False, False, False, True]
    assert all("read-only" in o["error"] for o in objects[:3])
    assert objects[3]["value"] == 1


def test_control_characters_from_the_controller_are_escaped_on_screen() -> None:
    from rac_console.commands.language import VarRef
    from rac_console.present.render import value_text

    shown = value_text(VarRef(kind_of("S"), 5), Variant(8, "A\x1b]0;x\x07B")).plain
    assert "\x1b" not in shown and "\\x1b" in shown
