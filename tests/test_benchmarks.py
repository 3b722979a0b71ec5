"""The benchmark suite runs, with tiny sizes, and reports every figure it promises."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"


def test_benchmark_smoke_run_reports_every_figure(tmp_path: Path) -> None:
    out = tmp_path / "figures.json"
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / "run.py"), "--smoke", "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    figures = json.loads(out.read_text())
    for key in (
        "client_to_bare_ratio",
        "responder_bare_python_rps",
        "simulator_client_rps",
        "simulator_50_sessions_rps",
        "watch_to_bare_ratio",
        "console_to_bare_ratio",
        "key_median_ms",
        "key_p95_ms",
        "cpu_ms_per_1000_frames",
        "memory_growth",
        "first_paint_s",
        "version_s",
    ):
        assert figures[key] > 0, key
    assert "session client / bare Python socket loop" in result.stdout
