"""Shared fixtures: the vendor vectors, and no test touches the real home."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from test_engine import Front

VECTORS = json.loads((Path(__file__).parent / "rac-samples.json").read_text())


@pytest.fixture(autouse=True)
def _private_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("XDG_STATE_HOME", str(home / ".local" / "state"))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(home / ".config"))


@pytest.fixture
def front() -> Iterator[Front]:
    """The engine on its own simulator (interval 0.05 s, timeout 1 s), drained as a
    front end would (``test_engine.Front``)."""
    from rac_console.engine import Engine

    engine = Engine(None, interval=0.05, timeout=1.0)
    engine.start()
    try:
        yield Front(engine)
    finally:
        engine.stop()
