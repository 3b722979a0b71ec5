"""A cell from the real CLI, run as a subprocess: ``-H a,b`` and ``--cell NAME`` open one
session per controller; ``watch`` names each line's target and exits with the worst
status over them; ``get``/``put`` name their target with ``@NAME``; ``run`` scripts route
``@NAME`` lines and ``use``. Two simulators in this process, on 127.0.0.1 port 0."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rac_console.protocol import kind_of
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import cli

pytestmark = pytest.mark.slow

I = kind_of("I")  # noqa: E741


@pytest.fixture
def two() -> Iterator[tuple[SimulatorThread, SimulatorThread]]:
    with SimulatorThread() as first, SimulatorThread() as second:
        yield first, second


def cell_config(first: SimulatorThread, second: SimulatorThread, extra: str = "") -> str:
    return (
        f'[target.cell3]\nhost = "127.0.0.1"\nport = {first.port}\n'
        f'[target.cell4]\nhost = "127.0.0.1"\nport = {second.port}\nwrites = "read-only"\n'
        f'[cell.line2]\ntargets = ["cell3", "cell4"]\n{extra}'
    )


def hosts(*sims: SimulatorThread) -> str:
    return ",".join(f"127.0.0.1:{sim.port}" for sim in sims)


def test_watch_on_two_targets_names_each_lines_target(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
) -> None:
    first, second = two
    first.server.controller.set("I", 5, 33)  # type: ignore[union-attr]
    second.server.controller.set("I", 5, 55)  # type: ignore[union-attr]
    done = cli(env, "-H", hosts(first, second), "watch", "I", "5", "--count", "2", "--every", "0")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert len(lines) == 4  # two cycles of each target
    a, b = f"127.0.0.1:{first.port}", f"127.0.0.1:{second.port}"
    assert sum(f"\t{a}.I5=33" in line for line in lines) == 2
    assert sum(f"\t{b}.I5=55" in line for line in lines) == 2


def test_watch_json_carries_the_profiles_name_as_target(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
    config: Callable[[str], Path],
) -> None:
    config(cell_config(*two))
    two[0].server.controller.set("I", 5, 33)  # type: ignore[union-attr]
    two[1].server.controller.set("I", 5, 55)  # type: ignore[union-attr]
    done = cli(env, "--cell", "line2", "watch", "I", "5", "--count", "1", "--json")
    assert done.returncode == 0, done.stderr
    by_target = {o["target"]: o for o in map(json.loads, done.stdout.splitlines())}
    assert by_target["cell3"]["values"] == {"I5": 33}
    assert by_target["cell4"]["values"] == {"I5": 55}


def test_one_target_down_is_that_targets_failure_and_the_worst_exit_status(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
) -> None:
    first, second = two
    first.server.controller.set("I", 5, 33)  # type: ignore[union-attr]
    gone = second.port
    second.stop()
    done = cli(
        env,
        "-H",
        f"127.0.0.1:{first.port},127.0.0.1:{gone}",
        "watch",
        "I",
        "5",
        "--count",
        "2",
        "--every",
        "0",
        "--timeout",
        "1",
    )
    assert done.returncode == 3, (done.stdout, done.stderr)  # a connection failure
    lines = done.stdout.splitlines()
    assert sum(f"127.0.0.1:{first.port}.I5=33" in line for line in lines) == 2  # still read
    assert any(f"127.0.0.1:{gone}.I5=!no-connection" in line for line in lines)
    assert f"127.0.0.1:{gone}.I5:" in done.stderr  # the failure names its target


def test_a_write_names_its_target_and_lands_on_that_controller_only(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
) -> None:
    first, second = two
    b = f"127.0.0.1:{second.port}"
    done = cli(env, "-H", hosts(first, second), "put", f"@{b}", "I", "10", "77", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["target"] == b
    assert second.server.controller.value(I, 10) == 77  # type: ignore[union-attr]
    assert first.server.controller.value(I, 10) != 77  # type: ignore[union-attr]


def test_a_write_without_its_target_is_refused_before_anything_is_sent(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
) -> None:
    first, second = two
    done = cli(env, "-H", hosts(first, second), "put", "I", "10", "77")
    assert done.returncode == 2
    assert "name the one to write first" in done.stderr and "Traceback" not in done.stderr
    assert first.server.controller.requests == second.server.controller.requests == 0


def test_a_targets_own_rules_apply_to_it_alone(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
    config: Callable[[str], Path],
) -> None:
    config(cell_config(*two))  # cell4 is read-only, cell3 open
    refused = cli(env, "--cell", "line2", "put", "@cell4", "I", "10", "5")
    assert refused.returncode == 2 and "read-only" in refused.stderr
    written = cli(env, "--cell", "line2", "put", "@cell3", "I", "10", "5")
    assert written.returncode == 0, written.stderr
    assert two[0].server.controller.value(I, 10) == 5  # type: ignore[union-attr]
    assert two[1].server.controller.value(I, 10) != 5  # type: ignore[union-attr]


def test_run_routes_at_name_lines_and_use(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
    config: Callable[[str], Path],
) -> None:
    config(cell_config(*two))
    two[0].server.controller.set("I", 5, 33)  # type: ignore[union-attr]
    two[1].server.controller.set("I", 5, 55)  # type: ignore[union-attr]
    script = "get I 5\n@cell4 get I 5\nuse cell4\nget I 5\n@cell9 get I 5\n"
    done = cli(env, "--cell", "line2", "run", "-", "--json", stdin=script)
    assert done.returncode == 2  # the line naming no open target
    results = [json.loads(line) for line in done.stdout.splitlines()]
    read = [(r["target"], r["value"]) for r in results if "value" in r and r.get("ok")]
    assert read == [("cell3", 33), ("cell4", 55), ("cell4", 55)]
    assert "no target named cell9" in done.stderr


def test_a_cell_that_is_not_in_the_config_says_which_are(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
    config: Callable[[str], Path],
) -> None:
    config(cell_config(*two))
    done = cli(env, "--cell", "line9", "watch", "I", "1", "--count", "1")
    assert done.returncode == 2
    assert "no cell named line9 (cells: line2)" in done.stderr and "Traceback" not in done.stderr


def test_a_cell_naming_a_missing_profile_is_one_line(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
    config: Callable[[str], Path],
) -> None:
    config(cell_config(*two).replace('"cell4"]', '"cell5"]'))
    done = cli(env, "--cell", "line2", "watch", "I", "1", "--count", "1")
    assert done.returncode == 2
    assert "no profile named cell5" in done.stderr and len(done.stderr.splitlines()) == 1


def test_watch_logs_one_csv_column_per_target_and_variable(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
    config: Callable[[str], Path],
    tmp_path: Path,
) -> None:
    config(cell_config(*two))
    two[0].server.controller.set("I", 5, 33)  # type: ignore[union-attr]
    two[1].server.controller.set("S", 1, "=cmd|' /C calc'!A0")  # type: ignore[union-attr]
    log = tmp_path / "cell.csv"
    done = cli(
        env,
        "--cell",
        "line2",
        "watch",
        "I",
        "5",
        "S",
        "1",
        "--count",
        "2",
        "--every",
        "0",
        "--log-csv",
        str(log),
    )
    assert done.returncode == 0, done.stderr
    rows = log.read_text(encoding="utf-8").splitlines()
    assert rows[0] == "time,cell3.I5,cell3.S1,cell4.I5,cell4.S1"
    assert len(rows) == 1 + 4  # two cycles of each target, a row each
    cell3 = [r for r in rows[1:] if r.split(",")[1] == "33"]
    assert len(cell3) == 2 and all(r.endswith(",,") for r in cell3)  # cell4's left empty
    assert any("'=cmd|" in r for r in rows[1:])  # a formula is text, not a formula


def test_run_on_a_cell_records_one_file_whose_lines_name_their_target(
    env: dict[str, str],
    two: tuple[SimulatorThread, SimulatorThread],
    config: Callable[[str], Path],
    tmp_path: Path,
) -> None:
    config(cell_config(*two))
    record, transcript = tmp_path / "cell.jsonl", tmp_path / "cell.log"
    done = cli(
        env,
        "--cell",
        "line2",
        "--record",
        str(record),
        "--log",
        str(transcript),
        "run",
        "-",
        stdin="get I 5\n@cell4 get I 5\n",
    )
    assert done.returncode == 0, done.stderr
    lines = [json.loads(line) for line in record.read_text(encoding="utf-8").splitlines()]
    assert [line["target"] for line in lines] == ["cell3", "cell3", "cell4", "cell4"]
    text = transcript.read_text(encoding="utf-8")
    assert " cell3 " in text and " cell4 " in text
