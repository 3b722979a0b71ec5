"""Pulled cables over a real network path: ``benchmarks/network_paths.py --quick`` runs
and its final line counts no wrong attribution and no wrong write report.

The script needs root, ``ip``, ``iptables`` and tmux to make two network namespaces;
where it cannot, it says why in one line and this test is skipped with that reason.
"""

from __future__ import annotations

import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

#: A minute or more of real timeouts, tmux and namespaces: `pytest -m "not slow"` skips it.
pytestmark = pytest.mark.slow

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "network_paths.py"
FINAL = re.compile(
    r"^network paths: (\d+) cases, wrong attributions (\d+), wrong write reports (\d+)$"
)
SKIPPED = "network paths: skipped: "


def test_pulled_cables_show_no_misattributed_value_and_no_wrong_write_report() -> None:
    process = subprocess.Popen(
        [sys.executable, str(SCRIPT), "--quick"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        out, err = process.communicate(timeout=600)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGINT)  # not a kill: its `finally` removes the namespaces
        out, err = process.communicate(timeout=120)
        pytest.fail(f"network_paths.py --quick ran over 600 s:\n{out[-2000:]}\n{err[-2000:]}")
    lines = out.strip().splitlines()
    last = lines[-1] if lines else ""
    if last.startswith(SKIPPED):
        pytest.skip(last.removeprefix(SKIPPED))
    assert process.returncode == 0, f"{out[-2000:]}\n{err[-2000:]}"
    found = FINAL.match(last)
    assert found, f"no final line:\n{out[-2000:]}\n{err[-2000:]}"
    cases, wrong_attributions, wrong_writes = map(int, found.groups())
    assert cases >= 4, out
    assert wrong_attributions == 0, out
    assert wrong_writes == 0, out
