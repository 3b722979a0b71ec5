"""The shared fixtures: a pytest plugin, registered by ``tests/conftest.py``
(``pytest_plugins``). A test asks for one by naming it as a parameter; no test imports
a fixture.

- ``env`` (every test): the private environment;
- ``recording``: :class:`~tests.support.servers.RecordingServer` s that stop with the test;
- ``front``: the engine on its own simulator, drained as a front end would;
- ``terminal``: a tmux server of the test's own (skips without tmux);
- ``utc``: local time is UTC (snapshots show clock times);
- ``config``: the config file the CLI reads (``RAC_CONSOLE_CONFIG`` in ``env``);
- ``broker``, ``subscriber``: a mosquitto of the test's own and a client on ``plant/#``;
- ``running``: commands a test leaves running, killed at its end;

and one mark, ``needs_mosquitto``.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rac_console.engine import Engine
from tests.support.brokers import Broker, Subscriber, mosquitto_path
from tests.support.drivers import Front, Running, Terminal
from tests.support.servers import Recording, RecordingServer, Reply, Sessions, sample_reply

#: The mark of a test that starts a real mosquitto: skipped where there is none.
needs_mosquitto = pytest.mark.skipif(
    mosquitto_path() is None, reason="mosquitto is not installed (.ci/run installs it)"
)


@pytest.fixture(autouse=True)
def env(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, str]:
    """No test touches the real home: HOME and the XDG directories point into the test's
    own ``tmp_path / "home"``, for this process and for the subprocesses a test starts.

    Every test gets it; a test that starts the CLI (or any program) asks for it by name
    and passes it on: the environment as it is here, plus UTF-8 pipes and 200 columns
    (so that a child's output is neither mis-encoded nor wrapped)."""
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(home / ".config"))
    monkeypatch.setenv("XDG_DATA_HOME", str(home / ".local" / "share"))
    monkeypatch.setenv("XDG_STATE_HOME", str(home / ".local" / "state"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(home / ".cache"))
    # No agent of the machine's user is found: a test's front ends go direct unless
    # the test starts an agent of its own there.
    runtime = home / "run"
    runtime.mkdir(mode=0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    if sys.platform == "win32":  # the user's runtime folder is Windows' own: told
        monkeypatch.setenv("RAC_CONSOLE_AGENT_DIR", str(runtime / "rac-console"))
    else:
        monkeypatch.delenv("RAC_CONSOLE_AGENT_DIR", raising=False)
    return dict(os.environ) | {"PYTHONIOENCODING": "utf-8", "COLUMNS": "200"}


@pytest.fixture
def recording() -> Iterator[Recording]:
    servers: list[RecordingServer] = []

    def make(
        reply: Reply = sample_reply, *, sessions: Sessions = "many", answers: int | None = None
    ) -> RecordingServer:
        server = RecordingServer(reply, sessions=sessions, answers=answers)
        servers.append(server)
        return server

    yield make
    for server in servers:
        server.close()


@pytest.fixture
def front() -> Iterator[Front]:
    """The engine on its own simulator (interval 0.05 s, timeout 1 s), drained as a
    front end would (:class:`~tests.support.drivers.Front`)."""
    engine = Engine(None, interval=0.05, timeout=1.0)
    engine.start()
    try:
        yield Front(engine)
    finally:
        engine.stop()


@pytest.fixture
def terminal(tmp_path: Path) -> Iterator[Terminal]:
    """A tmux server of the test's own, its HOME the test's ``tmp_path``."""
    if shutil.which("tmux") is None:
        pytest.skip("needs tmux")
    made = Terminal(tmp_path)
    yield made
    made.close()


@pytest.fixture
def utc(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()


@pytest.fixture
def config(tmp_path: Path, env: dict[str, str]) -> Callable[[str], Path]:
    """Write the config file the CLI reads (RAC_CONSOLE_CONFIG in ``env``)."""
    path = tmp_path / "config.toml"
    env["RAC_CONSOLE_CONFIG"] = str(path)

    def write(text: str) -> Path:
        path.write_text(text, encoding="utf-8")
        return path

    return write


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[Broker]:
    """A mosquitto of the test's own, stopped with it."""
    started = Broker(tmp_path).start()
    try:
        yield started
    finally:
        started.stop()


@pytest.fixture
def subscriber(broker: Broker) -> Iterator[Subscriber]:
    """Subscribed to ``plant/#`` on the test's broker."""
    watching = Subscriber(broker.port, "plant/#")
    try:
        yield watching
    finally:
        watching.close()


@pytest.fixture
def running() -> Iterator[list[Running]]:
    """Commands a test leaves running: killed at its end if still there."""
    started: list[Running] = []
    yield started
    for command in started:
        if command.process.poll() is None:
            command.process.kill()
            command.process.wait(20)
