"""The benchmark suite runs, with tiny sizes, and reports every figure it promises.

It checks that each figure is there and positive and that the table prints; never a
timing threshold (a shared CI machine cannot promise one).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.fixtures import needs_mosquitto

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"

FIGURES = (
    # one session against the responder, side by side, with CPU per request
    "bare_loop_rps",
    "bare_loop_cpu_us",
    "session_rps",
    "session_cpu_us",
    "session_to_bare_ratio",
    "engine_polls_per_s",
    "engine_cpu_us",
    "engine_to_session_ratio",
    "console_polls_per_s",
    "console_cpu_us",
    "console_to_session_ratio",
    "key_median_ms",
    "key_p95_ms",
    "cpu_ms_per_1000_frames",
    # 50 sessions: the simulator against the responder, the server's CPU per request
    "simulator_50_sessions_rps",
    "simulator_50_sessions_cpu_us",
    "responder_50_sessions_rps",
    "responder_50_sessions_cpu_us",
    "simulator_to_responder_50_ratio",
    # the console's memory and start-up
    "memory_10k_frames_mb",
    "memory_after_mb",
    "memory_growth",
    "first_paint_s",
    "version_s",
)
#: Measured only when a C compiler built the C programs.
C_FIGURES = ("c_client_rps", "c_client_cpu_us", "bare_to_c_ratio", "session_to_c_ratio")

ROWS = (
    "bare Python socket loop",
    "session client: Session.get",
    "engine: watch I 0-99, interval 0",
    "console: 100 watched, headless",
    "console: key to screen, p95",
    "simulator, 50 sessions",
)


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
    expected = FIGURES + (C_FIGURES if figures["meta"]["c_compiled"] else ())
    for key in expected:
        # CPU is read in clock ticks (10 ms): a process a smoke run keeps busy for less
        # than one, on a busy machine, reads 0. Every other figure is there and positive.
        assert figures[key] >= 0 if key.endswith("_cpu_us") else figures[key] > 0, key
    header = next(line for line in result.stdout.splitlines() if line.startswith("| path"))
    cells = [cell.strip() for cell in header.strip("|").split("|")]
    assert cells == ["path", "req/s", "µs CPU/request", "ratio", "target", "met?"]
    for row in ROWS:
        assert row in result.stdout, row
    assert "session client under cProfile" in result.stdout


def test_the_write_benchmark_reports_the_three_rates() -> None:
    result = subprocess.run(
        [sys.executable, "write_bench.py", "--count", "20", "--rounds", "1"],
        cwd=BENCHMARKS,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    (line,) = [text for text in result.stdout.splitlines() if text.startswith("round 0:")]
    for figure in ("bare PUT", "--no-verify", "verified"):
        assert figure in line, line


def test_the_floor_benchmark_reports_every_side_against_the_bare_loop(tmp_path: Path) -> None:
    out = tmp_path / "floor.json"
    result = subprocess.run(
        [sys.executable, "floor.py", "--rounds", "1", "--requests", "200", "--json", str(out)],
        cwd=BENCHMARKS,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    figures = json.loads(out.read_text())
    for side in ("get", "exchange", "latency", "execute", "engine"):
        assert figures[f"new.{side}.rate_to_bare"] > 0, side
        assert f"{side} " in result.stdout
    assert figures["new.bare.rate_to_bare"] == 1.0


def test_the_library_benchmark_prints_every_side_and_the_overhead(env: dict[str, str]) -> None:
    result = subprocess.run(
        [sys.executable, "library_get.py", "--rounds", "1", "--requests", "200"],
        cwd=BENCHMARKS,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    rows = {line.split()[0]: line.split()[1:] for line in result.stdout.splitlines()[2:6]}
    assert set(rows) == {"bare", "session", "library", "aio"}
    assert all(float(cells[0].replace(",", "")) > 0 for cells in rows.values())
    assert "library over Session.get: " in result.stdout and "µs a get" in result.stdout


@needs_mosquitto
@pytest.mark.skipif(
    shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler"
)
def test_the_plant_benchmark_prints_every_side_and_the_published_rate() -> None:
    pytest.importorskip("paho.mqtt.client")
    result = subprocess.run(
        [sys.executable, "plant_publish.py", "--quick"],
        cwd=BENCHMARKS,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    lines = result.stdout.splitlines()
    assert any(line.startswith("values") and "msgs acked/s" in line for line in lines)
    rows = {tuple(line.split()[:2]) for line in lines}
    for values in ("fixed", "changing"):
        for plant in ("off", "mqtt", "metrics"):
            assert (values, plant) in rows, (values, plant)
