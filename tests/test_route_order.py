"""Lines run one at a time, in the order typed, whatever target they name; ``run`` stops
at the first line that fails; the smaller defects of issue 30 (the quotes of ``wait ...
after``, a replayed cell's ports, a cell's watch list).

Writes are judged at fake controllers that record what they receive (127.0.0.1,
port 0); the test decides when each controller answers.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.commands.cells import MOST_WATCHED
from rac_console.commands.conditions import parse_wait
from rac_console.commands.target import Target
from rac_console.engine.cell.cell import Cell
from rac_console.engine.setup.options import EngineOptions
from rac_console.engine.setup.where import Where
from rac_console.engine.watch.watchlist import MAX_ROWS
from rac_console.present.history import History
from rac_console.sim.replay import read_targets
from rac_console.tui.app import RacConsoleApp
from tests.support.drivers import cli, results_text, type_line, until
from tests.support.servers import RecordingServer

Servers = Callable[..., RecordingServer]


def puts(server: RecordingServer) -> list[bytes]:
    return [line for line in server.lines if line.startswith(b"PUT:")]


def answers(line: bytes) -> bytes:
    """A controller whose every variable holds 0, and takes every PUT."""
    return b"0\r" if line.startswith(b"PUT:") else b"0,3,0\r"


def cell_config(a: int, b: int) -> str:
    return (
        f'[target.A]\nhost = "127.0.0.1"\nport = {a}\n'
        f'[target.B]\nhost = "127.0.0.1"\nport = {b}\n'
        '[cell.ab]\ntargets = ["A", "B"]\n'
    )


# ----------------------------------------------------------- the console's queue


@pytest.mark.slow
async def test_a_line_for_another_target_waits_for_the_line_typed_before_it(
    tmp_path: Path,
    recording: Servers,
) -> None:
    a, b = recording(answers), recording(answers)
    targets = [("A", Target("127.0.0.1", a.port)), ("B", Target("127.0.0.1", b.port))]
    cell = Cell(targets, options=EngineOptions(timeout=2.0, interval=0.05), where=Where.CONSOLE)
    app = RacConsoleApp(cell, History(tmp_path / "history"))
    async with app.run_test(size=(120, 40)) as pilot:
        await until(
            pilot,
            lambda: all(s.status for s in app.main_screen.members.states.values()),
            "the status",
        )
        await type_line(pilot, "wait I 10 == 999 within 60")
        await type_line(pilot, "@B put I 11 77")

        def reads_of_i10() -> int:
            return a.lines.count(b"GET:RC8:10:I:")

        await until(pilot, lambda: reads_of_i10() > 0, "the wait reading")
        started = reads_of_i10()
        # While A's wait reads on, B's put waits its turn: B receives nothing.
        await until(pilot, lambda: reads_of_i10() >= started + 20, "twenty more reads")
        assert puts(b) == [] and b.lines == []
        assert len(app.main_screen.lines.pending) == 2
        await pilot.press("escape")  # the wait and the put behind it end, on every target
        await until(pilot, lambda: not app.main_screen.lines.pending, "both lines answered")
        text = results_text(app)
        assert "not run" in text and text.index("wait") < text.index("not run")
    assert puts(b) == []


# --------------------------------------------------------------- run stops


@pytest.fixture
def ab(
    tmp_path: Path,
    env: dict[str, str],
    recording: Servers,
) -> tuple[RecordingServer, RecordingServer]:
    a, b = recording(answers), recording(answers)
    path = tmp_path / "config.toml"
    path.write_text(cell_config(a.port, b.port), encoding="utf-8")
    env["RAC_CONSOLE_CONFIG"] = str(path)
    return a, b


@pytest.mark.slow
def test_run_stops_at_a_line_that_names_no_target(
    ab: tuple[RecordingServer, RecordingServer],
    env: dict[str, str],
) -> None:
    a, b = ab
    result = cli(env, "--cell", "ab", "run", "-", stdin="use c\nput I 65 5\n")
    assert result.returncode == 2, result.stderr
    assert "line 1" in result.stderr and "no target named c" in result.stderr
    assert "stopped at line 1" in result.stderr
    assert puts(a) == [] and puts(b) == []
    # Names are found in any case: use b is B.
    moved = cli(env, "--cell", "ab", "--no-verify", "run", "-", stdin="use b\nput I 65 5\n")
    assert moved.returncode == 0, moved.stderr
    assert puts(a) == [] and puts(b) == [b"PUT:RC8:65:I:3,5"]


@pytest.mark.slow
def test_run_stops_after_a_wait_not_met_unless_told_to_keep_going(
    ab: tuple[RecordingServer, RecordingServer],
    env: dict[str, str],
) -> None:
    a, _ = ab
    script = "wait I 10 == 999 within 0.3\nput I 65 5\n"
    stopped = cli(env, "--cell", "ab", "run", "-", stdin=script)
    assert stopped.returncode not in (0, 2), stopped.stderr  # the wait's own status
    assert "stopped at line 1" in stopped.stderr
    assert puts(a) == []
    going = cli(env, "--cell", "ab", "run", "--keep-going", "-", stdin=script)
    assert going.returncode == stopped.returncode
    assert puts(a) == [b"PUT:RC8:65:I:3,5"]


@pytest.mark.slow
def test_run_on_one_target_stops_at_a_refused_line(
    env: dict[str, str],
    recording: Servers,
) -> None:
    server = recording(answers)
    script = "put I 10 nope\nput I 11 5\n"
    result = cli(env, *server.args, "--json", "run", "-", stdin=script)
    assert result.returncode == 2
    [refusal] = [json.loads(line) for line in result.stdout.splitlines()]
    assert refusal["line"] == 1 and not refusal["ok"]
    assert server.lines == []


# ----------------------------------------------------------- the smaller ones


def test_after_inside_quotes_is_part_of_the_string() -> None:
    wait = parse_wait('S 1 == "x after @B I 11 == 78"')
    assert wait.after is None and wait.value_text == '"x after @B I 11 == 78"'
    chained = parse_wait('S 1 == "a after @B" after @A I 1 == 2')
    assert chained.after is not None and chained.after.target == "A"
    assert chained.value_text == '"a after @B"'


def _frames(target: str, place: int | None, value: int) -> list[bytes]:
    extra = {} if place is None else {"member": place}
    tx = {"t": 1.0, "target": target, **extra, "dir": "tx", "text": "GET:RC8:1:I:"}
    rx = {"t": 1.1, "target": target, **extra, "dir": "rx", "text": f"0,3,{value}"}
    return [json.dumps(tx).encode() + b"\n", json.dumps(rx).encode() + b"\n"]


def test_a_replayed_cell_serves_its_targets_in_the_cells_order() -> None:
    lines = _frames("robotB", 2, 2) + _frames("robotA", 1, 1)  # B wrote first
    assert [r.target for r in read_targets(lines, "cell.jsonl")] == ["robotA", "robotB"]
    unplaced = _frames("zeta", None, 2) + _frames("alpha", None, 1)
    assert [r.target for r in read_targets(unplaced, "old.jsonl")] == ["alpha", "zeta"]


@pytest.mark.slow
def test_a_recorded_cell_records_each_targets_place(
    tmp_path: Path,
    ab: tuple[RecordingServer, RecordingServer],
    env: dict[str, str],
) -> None:
    record = tmp_path / "cell.jsonl"
    result = cli(
        env, "--cell", "ab", "--record", str(record), "run", "-", stdin="@B get I 1\n@A get I 1\n"
    )
    assert result.returncode == 0, result.stderr
    records = [json.loads(line) for line in record.read_text(encoding="utf-8").splitlines()]
    assert {(r["target"], r["member"]) for r in records} == {("A", 1), ("B", 2)}
    assert records[0]["target"] == "B"
    ordered = read_targets(record.read_bytes().splitlines(keepends=True), str(record))
    assert [r.target for r in ordered] == ["A", "B"]


@pytest.mark.slow
def test_a_cells_watch_list_is_capped_like_a_watch_file(
    tmp_path: Path,
    env: dict[str, str],
) -> None:
    assert MOST_WATCHED == MAX_ROWS
    lines = ", ".join(f'"A I {n}"' for n in range(MOST_WATCHED + 1))
    path = tmp_path / "config.toml"
    path.write_text(
        cell_config(5006, 5007).replace(
            'targets = ["A", "B"]', f'targets = ["A", "B"]\nwatch = [{lines}]'
        ),
        encoding="utf-8",
    )
    env["RAC_CONSOLE_CONFIG"] = str(path)
    result = cli(env, "--cell", "ab", "watch", "I", "1", "--count", "1")
    assert result.returncode == 2
    [line] = result.stderr.strip().splitlines()
    assert f"at most {MOST_WATCHED}" in line
