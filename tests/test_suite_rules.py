"""The test suite's own rules: tests share helpers through ``tests/support`` (a driver
module, a server factory, fixtures from a plugin), never by importing each other, and
never import a fixture by name (which needed a ``noqa`` for ruff's F811 where the
fixture was then used as a parameter). And one rule of the package's: no module of it
grows past :data:`MOST_LINES`."""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).parent
SUPPORT = TESTS / "support"
TEST_MODULES = sorted(TESTS.glob("test_*.py"))
#: The modules of tests/ that are not tests.
NOT_TESTS = {"__init__.py", "conftest.py"}
PACKAGE = TESTS.parent / "rac_console"
#: The most lines a module of the package may hold (a few hundred, the style says): one
#: that grows past it is split at a seam, as commands/exchange_parsers.py was. No module
#: is excepted.
MOST_LINES = 500


def imported_modules(path: Path) -> list[tuple[int, str]]:
    """Every module ``path`` imports (at any depth), as written, with its line; a
    relative import as ``.name`` (one dot per level)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            module = "." * node.level + (node.module or "")
            found.append((node.lineno, module))
            if node.module is None:  # from . import test_x
                found += [(node.lineno, "." * node.level + a.name) for a in node.names]
    return found


def is_test_module(module: str) -> bool:
    """``test_cli``, ``tests.test_cli``, ``.test_cli``, ``conftest``: a module of tests,
    not of tests/support."""
    last = module.rsplit(".", 1)[-1]
    return last.startswith("test_") or last == "conftest"


def fixture_names() -> set[str]:
    """The fixtures tests/support/fixtures.py defines (``@pytest.fixture``)."""
    names = set()
    tree = ast.parse((SUPPORT / "fixtures.py").read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            for decorator in node.decorator_list:
                target = decorator.func if isinstance(decorator, ast.Call) else decorator
                if ast.unparse(target) in ("pytest.fixture", "fixture"):
                    names.add(node.name)
    return names


def test_the_rules_see_the_suite() -> None:
    assert len(TEST_MODULES) > 100
    assert "env" in fixture_names() and "recording" in fixture_names()


def test_no_test_module_imports_another() -> None:
    offenders = [
        f"{path.name}:{line}: {module}"
        for path in [*TEST_MODULES, *SUPPORT.glob("*.py"), TESTS / "conftest.py"]
        for line, module in imported_modules(path)
        if is_test_module(module)
    ]
    assert offenders == [], "helpers go in tests/support:\n" + "\n".join(offenders)


def test_helpers_live_in_tests_support() -> None:
    """Nothing in tests/ but tests, conftest.py and the package's __init__.py: a helper
    module beside the tests is a module the tests would import from each other."""
    strays = [
        path.name
        for path in TESTS.glob("*.py")
        if not path.name.startswith("test_") and path.name not in NOT_TESTS
    ]
    assert strays == []


def test_no_fixture_is_imported_by_name() -> None:
    fixtures = fixture_names()
    offenders = []
    for path in [*TEST_MODULES, *SUPPORT.glob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").endswith("fixtures"):
                offenders += [
                    f"{path.name}:{node.lineno}: {alias.name}"
                    for alias in node.names
                    if alias.name in fixtures
                ]
    assert offenders == [], "ask for a fixture as a parameter:\n" + "\n".join(offenders)


def test_no_noqa_f811() -> None:
    """A ``noqa`` for F811 (a redefinition) marked a fixture imported by name and then
    used as a parameter."""
    marker = "noqa: " + "F811"  # not written whole here, so this file does not match
    offenders = [
        f"{path.relative_to(TESTS)}:{number}"
        for path in TESTS.rglob("*.py")
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if marker in line
    ]
    assert offenders == []


def test_no_module_of_the_package_is_over_most_lines() -> None:
    sizes = {
        str(path.relative_to(PACKAGE)): len(path.read_text(encoding="utf-8").splitlines())
        for path in sorted(PACKAGE.rglob("*.py"))
    }
    over = {name: lines for name, lines in sizes.items() if lines > MOST_LINES}
    assert len(sizes) > 100  # the rule sees the package
    assert over == {}, f"over {MOST_LINES} lines (split each at a seam): {over}"
