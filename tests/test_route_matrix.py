"""One line, one controller, in every front end (issue 30): the same table of cases
through the one-shot CLI and ``run`` (subprocesses), the REPL and the console (built
from the same command line, in this process).

Three fake controllers record what they receive: ``bench`` (writes open), ``ro``
(read-only) and, at ro's endpoint under another name, ``rw2`` (writes open: the
stricter rules of the two apply). Each way of naming a target is tried with each way
of writing, every write to its own index, and judged from the controllers' side: which
indices reached bench, and that ro received no PUT at all.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from rac_console.cli.main import make_cell, parse_args, settle_targets
from rac_console.engine.cell.cell import Cell
from rac_console.present.history import History
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import Driver, cli, type_line, until
from tests.support.servers import RecordingServer

pytestmark = pytest.mark.slow


@dataclass(frozen=True)
class Case:
    """A way of naming the target (``{bench}``, ``{ro}``: the ports), the lines tried
    (each writes its own index) and the indices that must reach bench."""

    hosts: tuple[str, ...]
    lines: tuple[tuple[str, int], ...]
    to_bench: frozenset[int]


#: The write forms on one target: put, send PUT:, a raw PUT: line.
ONE = (("put I 10 5", 10), ("send PUT:RC8:11:I:3,5", 11), ("PUT:RC8:12:I:3,5", 12))
ALL = frozenset({10, 11, 12})
NONE: frozenset[int] = frozenset()

CASES = {
    "name": Case(("-H", "bench"), ONE, ALL),
    "name in another case": Case(("-H", "BENCH"), ONE, ALL),
    "name with another port": Case(("-H", "bench:{ro}"), ONE, NONE),
    "name with -p": Case(("-H", "bench", "-p", "{ro}"), ONE, NONE),
    "address": Case(("-H", "127.0.0.1:{bench}"), ONE, ALL),
    "address as localhost": Case(("-H", "localhost", "-p", "{bench}"), ONE, ALL),
    "ro's address as 127.1": Case(("-H", "127.1:{ro}"), ONE, NONE),
    "a second profile at ro's endpoint": Case(("-H", "rw2"), ONE, NONE),
    "cell members": Case(
        ("-H", "ro,bench"),
        (
            ("put I 10 5", 10),  # the current target: ro
            ("@bench put I 11 5", 11),
            ("@RO put I 12 5", 12),
            ("@Bench send PUT:RC8:13:I:3,5", 13),
            ("@ro PUT:RC8:14:I:3,5", 14),
            ("@bench PUT:RC8:15:I:3,5", 15),
        ),
        frozenset({11, 13, 15}),
    ),
}


def reply(line: bytes) -> bytes:
    return b"0\r" if line.startswith(b"PUT:") else b"0,3,5\r"


@dataclass
class Plant:
    bench: RecordingServer
    ro: RecordingServer

    def words(self, case: Case) -> list[str]:
        return [w.format(bench=self.bench.port, ro=self.ro.port) for w in case.hosts]

    def check(self, case: Case) -> None:
        """Judged from the controllers' side."""
        ro_puts = [line for line in self.ro.lines if line.startswith(b"PUT:")]
        assert ro_puts == [], "the read-only endpoint received a write"
        reached = {
            int(line.split(b":")[2]) for line in self.bench.lines if line.startswith(b"PUT:")
        }
        assert reached == case.to_bench


def config_text(bench: int, ro: int) -> str:
    return (
        f'[target.bench]\nhost = "127.0.0.1"\nport = {bench}\n'
        f'[target.ro]\nhost = "127.0.0.1"\nport = {ro}\nwrites = "read-only"\n'
        f'[target.rw2]\nhost = "localhost"\nport = {ro}\n'
    )


@pytest.fixture
def plant(
    tmp_path: Path,
    env: dict[str, str],
    recording: Callable[..., RecordingServer],
    monkeypatch: pytest.MonkeyPatch,
) -> Iterator[Plant]:
    bench, ro = recording(reply), recording(reply)
    path = tmp_path / "config.toml"
    path.write_text(config_text(bench.port, ro.port), encoding="utf-8")
    env["RAC_CONSOLE_CONFIG"] = str(path)
    monkeypatch.setenv("RAC_CONSOLE_CONFIG", str(path))  # the REPL and the console here
    yield Plant(bench, ro)


# ------------------------------------------------------------------- the CLI


@pytest.mark.parametrize("name", CASES)
def test_one_shot(name: str, plant: Plant, env: dict[str, str]) -> None:
    case = CASES[name]
    several = "," in "".join(case.hosts)
    tried = set()
    for line, index in case.lines:
        target, rest = "", line
        if line.startswith("@"):
            target, _, rest = line.partition(" ")
        if rest.startswith("PUT:") or (several and not target):
            continue  # a raw line is no one-shot command; a cell's names its target first
        word, _, words = rest.partition(" ")
        argv = [*plant.words(case), word, *([target] if target else []), *words.split()]
        result = cli(env, *argv)
        assert "Traceback" not in result.stderr
        assert result.returncode == (0 if index in case.to_bench else 2), result.stderr
        tried.add(index)
    plant.check(Case(case.hosts, case.lines, case.to_bench & tried))


@pytest.mark.parametrize("name", CASES)
def test_run(name: str, plant: Plant, env: dict[str, str]) -> None:
    case = CASES[name]
    script = "".join(f"{line}\n" for line, _ in case.lines)
    result = cli(env, *plant.words(case), "run", "--keep-going", "-", stdin=script)
    assert "Traceback" not in result.stderr
    assert result.returncode == (0 if case.to_bench == {i for _, i in case.lines} else 2)
    plant.check(case)


# ------------------------------------------------------- the REPL and the console


def cell_of(plant: Plant, case: Case, repl: bool) -> Cell:
    args = parse_args([*plant.words(case), *(["repl"] if repl else []), "--timeout", "2"])
    assert settle_targets(args) is not False
    return make_cell(args)


class CellDriver(Driver):
    """The REPL (:class:`~tests.support.drivers.Driver`) on a pipe, over a cell made from a
    command line."""

    def __init__(self, tmp_path: Path, cell: Cell) -> None:
        self.cell = cell
        super().__init__(tmp_path)

    def make_engine(self, host: str | None, **options: object) -> Cell:  # type: ignore[override]
        return self.cell


@pytest.mark.parametrize("name", CASES)
async def test_repl(name: str, plant: Plant, tmp_path: Path) -> None:
    case = CASES[name]
    driver = CellDriver(tmp_path, cell_of(plant, case, repl=True))

    async def steps(d: Driver) -> None:
        for line, _ in case.lines:
            d.type(f"{line}\r")
        d.type("help unwatch\r")  # lines run in turn: its answer comes after theirs
        await d.until(lambda out: "unwatch TYPE INDEX" in out, "every line answered", 20)

    await driver.run(steps)
    plant.check(case)


@pytest.mark.parametrize("name", CASES)
async def test_console(name: str, plant: Plant, tmp_path: Path) -> None:
    case = CASES[name]
    app = RacConsoleApp(cell_of(plant, case, repl=False), History(tmp_path / "history"))
    async with app.run_test(size=(120, 40)) as pilot:
        await until(
            pilot,
            lambda: all(s.status for s in app.main_screen.members.states.values()),
            "the status",
        )
        for line, _ in case.lines:
            await type_line(pilot, line)
        await until(pilot, lambda: not app.main_screen.lines.pending, "every line answered")
    plant.check(case)
