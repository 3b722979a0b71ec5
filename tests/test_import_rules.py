"""The layers show in the imports: pure code stays pure, only two modules touch sockets,
and the layers contract in pyproject.toml (import-linter) holds."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

PACKAGE = Path(__file__).parent.parent / "rac_console"
PURE_MODULES = [
    "rac_console.protocol",
    "rac_console.protocol.variant",
    "rac_console.protocol.messages",
    "rac_console.protocol.variables",
    "rac_console.protocol.framing",
    "rac_console.commands.argv",
    "rac_console.commands.check",
    "rac_console.commands.language",
    "rac_console.commands.outcome",
    "rac_console.commands.profiles",
    "rac_console.commands.target",
    "rac_console.protocol.request",
    "rac_console.sim.controller",
]
FORBIDDEN_IN_PURE = ["asyncio", "socket", "selectors", "textual", "prompt_toolkit", "rich"]
SOCKET_OWNERS = {
    "session/blocking.py",
    "session/diagnose.py",
    "session/endpoints.py",
    "sim/server.py",  # the simulator's server: its listener and accept loop,
    "sim/session.py",  # each connection,
    "sim/lane.py",  # and the epoll lane that serves connections on Linux
    "plant/metrics_server.py",  # /metrics: its listener and connections, on one thread
}
SOCKET_CALLS = {
    "create_connection",
    "create_server",
    "open_connection",
    "start_server",
    "sock_connect",
    "socket",
}


@pytest.mark.parametrize("module", PURE_MODULES)
def test_pure_modules_import_no_io_or_ui(module: str) -> None:
    probe = (
        f"import sys, {module}\n"
        f"bad = [m for m in {FORBIDDEN_IN_PURE!r} if m in sys.modules]\n"
        "print(','.join(bad))"
    )
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "", f"{module} pulls in {result.stdout.strip()}"


def _socket_uses(path: Path) -> list[str]:
    tree = ast.parse(path.read_text())
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import) and any(a.name == "socket" for a in node.names):
            found.append("import socket")
        elif isinstance(node, ast.ImportFrom) and node.module == "socket":
            found.append("from socket import")
        elif isinstance(node, ast.Attribute) and node.attr in SOCKET_CALLS:
            found.append(node.attr)
    return found


def test_the_layers_contract_holds() -> None:
    """pyproject.toml's import-linter contracts: each layer imports only the ones below
    it; no toolkit below the front ends; no rich below present/."""
    result = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; from importlinter.cli import lint_imports_command; "
            "sys.exit(lint_imports_command())",
        ],
        capture_output=True,
        text=True,
        cwd=PACKAGE.parent,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]


def test_only_the_session_and_the_simulator_server_touch_sockets() -> None:
    offenders = {}
    for path in PACKAGE.rglob("*.py"):
        relative = path.relative_to(PACKAGE).as_posix()
        if relative not in SOCKET_OWNERS and (uses := _socket_uses(path)):
            offenders[relative] = uses
    assert offenders == {}


def test_version_starts_without_importing_ui_toolkits() -> None:
    probe = (
        "import sys\nfrom rac_console.cli.main import build_parser\n"
        "print([m for m in ('textual', 'prompt_toolkit', 'rich', 'asyncio')"
        " if m in sys.modules])"
    )
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"


@pytest.mark.parametrize(
    "module, toolkit",
    [
        ("rac_console.repl.repl", "textual"),
        ("rac_console.tui.app", "prompt_toolkit"),
        ("rac_console.cli.oneshot", "textual"),
    ],
)
def test_each_front_end_loads_only_its_own_toolkit(module: str, toolkit: str) -> None:
    probe = f"import sys, {module}\nprint({toolkit!r} in sys.modules)"
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "False"
