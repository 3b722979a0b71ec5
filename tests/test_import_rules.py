"""The layers show in the imports: pure code stays pure, only the session, the
simulator's server and the plant's /metrics touch sockets, the contracts in
pyproject.toml (import-linter) hold, and no import circle closes anywhere in the package."""

from __future__ import annotations

import ast
import subprocess
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    import grimp
else:  # its compiled core does not load under Wine: the Windows lane skips these
    grimp = pytest.importorskip("grimp", reason="grimp's compiled extension does not load")

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
    "rac_console.commands.exchange_parsers",
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
    "session/sockets.py",  # the session's socket below the protocol: options, peeks, resets
    "session/diagnose.py",
    "session/endpoints.py",
    "sim/server.py",  # the simulator's server: its listener and accept loop,
    "sim/session.py",  # each connection,
    "sim/lane.py",  # and the epoll lane that serves connections on Linux
    "plant/metrics_server.py",  # /metrics: its listener and connections, on one thread
    "agent/endpoint.py",  # the agent's listener, and a client's connection to it
    "agent/wire.py",  # the messages on one such connection
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


# ------------------------------------------------------------- import circles


def strongly_connected(graph: Mapping[str, Iterable[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components of ``graph`` (each node to the nodes it
    imports), each sorted; without recursion: a stack of (node, successors left)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)

    for root in graph:
        if root in index:
            continue
        visit(root)
        work = [(root, iter(graph[root]))]
        while work:
            node, successors = work[-1]
            for successor in successors:
                if successor not in index:
                    visit(successor)
                    work.append((successor, iter(graph[successor])))
                    break
                if successor in on_stack:
                    low[node] = min(low[node], index[successor])
            else:  # every successor seen: node is done
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[node])
                if low[node] == index[node]:  # the root of a component: pop it whole
                    component: list[str] = []
                    while not component or component[-1] != node:
                        component.append(stack.pop())
                        on_stack.discard(component[-1])
                    components.append(sorted(component))
    return components


def import_circles(graph: grimp.ImportGraph) -> list[str]:
    """Each circle in ``graph``, as its modules and the imports that close it: the
    strongly connected components of more than one module, or of one importing itself."""
    edges = {m: sorted(graph.find_modules_directly_imported_by(m)) for m in graph.modules}
    circles = []
    for component in strongly_connected(dict(sorted(edges.items()))):
        members = set(component)
        if len(component) == 1 and component[0] not in edges[component[0]]:
            continue
        lines = [f"a circle of {len(component)}: {', '.join(component)}"]
        for importer in component:
            for imported in (m for m in edges[importer] if m in members):
                details = graph.get_import_details(importer=importer, imported=imported)
                where = ", ".join(f"line {d['line_number']}" for d in details)
                lines.append(f"    {importer} -> {imported} ({where})")
        circles.append("\n".join(lines))
    return circles


def test_the_circle_finder_finds_circles_and_only_circles() -> None:
    graph = {
        "a": ["b"],
        "b": ["c", "d"],
        "c": ["a"],  # a -> b -> c -> a
        "d": ["e"],
        "e": [],
        "f": ["f"],  # a module importing itself
        "g": ["a", "h"],
        "h": ["g"],  # g <-> h, apart from a, b, c though g imports a
    }
    found = sorted(strongly_connected(graph))
    assert found == [["a", "b", "c"], ["d"], ["e"], ["f"], ["g", "h"]]
    chain = {f"m{n}": [f"m{n + 1}"] for n in range(5000)} | {"m5000": ["m0"]}
    assert [len(c) for c in strongly_connected(chain)] == [5001]  # no recursion limit


def test_a_circle_for_types_only_is_found(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """grimp counts imports made for the type checker alone (under TYPE_CHECKING): a
    package whose two modules import each other only so is one circle."""
    package = tmp_path / "typed_circle"
    package.mkdir()
    (package / "__init__.py").write_text("")
    for name, other in (("one", "two"), ("two", "one")):
        (package / f"{name}.py").write_text(
            "from typing import TYPE_CHECKING\n"
            f"if TYPE_CHECKING:\n    from .{other} import X\nX = 1\n"
        )
    monkeypatch.syspath_prepend(str(tmp_path))
    graph = grimp.build_graph("typed_circle", cache_dir=None)
    assert [c.splitlines()[0] for c in import_circles(graph)] == [
        "a circle of 2: typed_circle.one, typed_circle.two"
    ]


def test_no_import_circle_anywhere_in_the_package() -> None:
    """No module of rac_console comes back to itself through its imports, whether at
    run time or for types only (TYPE_CHECKING imports are edges too): the whole graph,
    not one package's siblings as import-linter's acyclic_siblings contracts check.

    Every edge counts, a package's ``__init__`` importing its own modules included (to
    re-export their names, lazily or for the type checker). That edge alone closes no
    circle: one closes only when a module imports its own package's ``__init__`` and
    the ``__init__`` leads back to it, and such a circle is real (the module needs what
    the ``__init__`` gives, which comes from modules that need the module). The cure is
    to import the sibling module itself, not the package's re-export. (``cli.parser``
    and ``tui.app`` import ``rac_console`` for its version: its ``__init__`` imports
    nothing, so no circle.)"""
    graph = grimp.build_graph(
        "rac_console",
        include_external_packages=False,
        exclude_type_checking_imports=False,
        cache_dir=None,
    )
    circles = import_circles(graph)
    assert not circles, "import circles in rac_console:\n" + "\n".join(circles)
