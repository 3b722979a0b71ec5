"""A cell: one engine per controller behind one front end. Lines go to ``@NAME`` or to
the current target (``use NAME``), each write to one controller under its own rules;
one controller down leaves the others polling. Real simulators over real sockets; the
REPL driven through prompt-toolkit's pipe input."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.commands.cells import parse_cells, split_address, split_hosts
from rac_console.commands.policy import WritePolicy, Writes
from rac_console.commands.target import Target
from rac_console.engine import Result
from rac_console.engine.cell.cell import Cell
from rac_console.protocol import InputError, kind_of
from rac_console.sim.thread import SimulatorThread
from tests.support.cells import CellFront
from tests.support.drivers import Driver

I = kind_of("I")  # noqa: E741


@pytest.fixture
def sims() -> Iterator[list[SimulatorThread]]:
    with SimulatorThread() as a, SimulatorThread() as b, SimulatorThread() as c:
        yield [a, b, c]


def open_cell(sims: list[SimulatorThread], **rules: Target) -> Cell:
    names = ["robotA", "robotB", "robotC"][: len(sims)]
    targets = [rules.get(n) or Target(s.host, s.port) for n, s in zip(names, sims, strict=True)]
    cell = Cell(list(zip(names, targets, strict=True)))
    cell.start()
    return cell


def text(result: Result) -> str:
    return " ".join(str(getattr(f, "text", f)) for f in result.feedback)


def test_lines_go_to_their_at_name_or_to_the_current_target(sims: list[SimulatorThread]) -> None:
    cell = open_cell(sims)
    drained = CellFront(cell)
    try:
        put_b = cell.submit("@robotB put I 10 7")
        put_current = cell.submit("put I 11 8")
        use = cell.submit("use robotC")
        put_c = cell.submit("put I 12 9")
        assert drained.result(put_b)[0] == "robotB"
        assert drained.result(put_current)[0] == "robotA"
        assert drained.result(use)[0] is None and "current target: robotC" in text(
            drained.result(use)[1]
        )
        assert drained.result(put_c)[0] == "robotC"
        assert len({put_b, put_current, use, put_c}) == 4  # one number, one job in the cell
    finally:
        cell.stop()
    values = [[s.server.controller.value(I, n) for n in (10, 11, 12)] for s in sims]  # type: ignore[union-attr]
    assert values[0][1] == 8 and values[1][0] == 7 and values[2][2] == 9
    assert values[0][0] != 7 and values[2][0] != 7 and values[1][1] != 8 and values[1][2] != 9


def test_a_line_for_a_target_that_is_not_open_is_refused_and_nothing_is_sent(
    sims: list[SimulatorThread],
) -> None:
    cell = open_cell(sims[:2])
    drained = CellFront(cell)
    try:
        before = [s.server.controller.requests for s in sims[:2]]
        seq = cell.submit("@robotZ put I 10 7")
        name, result = drained.result(seq)
        assert name is None and "no target named robotZ" in text(result)
        assert "open: robotA, robotB" in text(result)
        refused = cell.submit("connect 127.0.0.1")
        assert "a cell's targets are fixed" in text(drained.result(refused)[1])
    finally:
        cell.stop()
    assert [s.server.controller.requests for s in sims[:2]] == before


def test_each_targets_rules_apply_to_it_alone(sims: list[SimulatorThread]) -> None:
    read_only = Target(
        sims[1].host, sims[1].port, policy=WritePolicy(Writes.READ_ONLY), read_only=True
    )
    cell = open_cell(sims[:2], robotB=read_only)
    drained = CellFront(cell)
    try:
        refused = cell.submit("@robotB put I 10 7")
        written = cell.submit("@robotA put I 10 7")
        assert "read-only" in text(drained.result(refused)[1])
        drained.result(written)
    finally:
        cell.stop()
    assert sims[0].server.controller.value(I, 10) == 7  # type: ignore[union-attr]
    assert sims[1].server.controller.value(I, 10) != 7  # type: ignore[union-attr]


def test_one_controller_down_leaves_the_others_polling(sims: list[SimulatorThread]) -> None:
    cell = open_cell(sims[:2])
    drained = CellFront(cell)
    try:
        for name in ("robotA", "robotB"):
            drained.result(cell.submit(f"@{name} watch I 0"))  # I 0 counts at 10 Hz
        drained.result(cell.submit("@robotA interval 0.05"))
        drained.result(cell.submit("@robotB interval 0.05"))
        sims[1].stop()

        def row(name: str):
            rows = [b.rows for b in drained.batches.get(name, []) if b.rows]
            return next((r for batch in reversed(rows) for r in batch.values()), None)

        drained.until(lambda: (r := row("robotB")) is not None and r.stale, "robotB's row stale")
        seen = row("robotA")
        assert seen is not None and not seen.stale
        drained.until(
            lambda: (r := row("robotA")) is not None and r.variant != seen.variant,
            "robotA's value still moving",
        )
    finally:
        cell.stop()


def test_the_pure_parts() -> None:
    assert split_hosts("cell3") is None and split_hosts("cell3,cell4") == ["cell3", "cell4"]
    with pytest.raises(InputError, match="twice"):
        split_hosts("cell3,cell3")
    with pytest.raises(InputError, match="missing between commas"):
        split_hosts("cell3,,cell4")
    assert split_address("@cell4 get I 10") == ("cell4", "get I 10")
    assert split_address("get I 10") == (None, "get I 10")
    with pytest.raises(InputError, match="needs a command"):
        split_address("@cell4")
    from rac_console.commands.routing import OnTarget, Refused
    from rac_console.engine.commands.builtin import BUILTIN

    routed = BUILTIN.plan("get I 1", ["a", "b"], "b")
    assert isinstance(routed, OnTarget) and (routed.name, routed.text) == ("b", "get I 1")
    refused = BUILTIN.plan("@c get I 1", ["a", "b"], "a")
    assert isinstance(refused, Refused) and "open: a, b" in refused.text

    def fail(text: str) -> InputError:
        return InputError(text)

    cells = parse_cells(
        {"l2": {"targets": ["a", "b"], "watch": ["a IO 128 placed"]}}, {"a": 1, "b": 2}, fail
    )
    assert cells["l2"].targets == ("a", "b") and cells["l2"].watch == ("a IO 128 placed",)
    with pytest.raises(InputError, match="no profile named c"):
        parse_cells({"l2": {"targets": ["a", "c"]}}, {"a": 1}, fail)
    with pytest.raises(InputError, match="start with one of its targets"):
        parse_cells({"l2": {"targets": ["a"], "watch": ["IO 128"]}}, {"a": 1}, fail)


async def test_the_repl_prompt_names_the_current_target_and_at_name_runs_elsewhere(
    tmp_path: Path, sims: list[SimulatorThread]
) -> None:
    sims[1].server.controller.set("I", 5, 55)  # type: ignore[union-attr]
    sims[0].server.controller.set("I", 5, 33)  # type: ignore[union-attr]
    cell = Cell(
        [
            ("robotA", Target(sims[0].host, sims[0].port)),
            ("robotB", Target(sims[1].host, sims[1].port)),
        ]
    )
    driver = Driver(tmp_path, screen=True)
    driver.engine = cell  # type: ignore[assignment]

    async def steps(d: Driver) -> None:
        await d.until(lambda out: "robotA\x1b[0m ›" in out, "the prompt naming robotA")
        d.type("get I 5\r")
        await d.until(lambda out: "robotA › I5 = 33" in out, "robotA's value")
        d.type("@robotB get I 5\r")
        await d.until(lambda out: "robotB › I5 = 55" in out, "robotB's value")
        d.type("use robotB\r")
        await d.until(lambda out: "current target: robotB" in out, "use")
        d.type("put I 6 66\r")
        await d.until(lambda out: "robotB › I6: " in out, "the write naming robotB")

    out = await driver.run(steps)
    assert "robotB\x1b[0m ›" in out  # the prompt after use
    assert sims[1].server.controller.value(I, 6) == 66  # type: ignore[union-attr]
    assert sims[0].server.controller.value(I, 6) != 66  # type: ignore[union-attr]


@pytest.mark.slow  # over half a second
def test_a_wait_after_another_targets_condition_says_the_delay_between_them() -> None:
    from rac_console.sim.cell import SimulatedCellThread

    with SimulatedCellThread(2, cycle=1.0, hold=0.5, reaction=0.2) as simulated:
        (a, host_a, port_a), (b, host_b, port_b) = simulated.cell.addresses
        cell = Cell([(a, Target(host_a, port_a)), (b, Target(host_b, port_b))])
        cell.start()
        drained = CellFront(cell)
        try:
            seq = cell.submit(f"@{b} wait IO 64 on within 3 after @{a} IO 128 on")
            name, result = drained.result(seq)
            never = cell.submit(f"@{b} wait IO 65 on within 0.3 after @{a} IO 128 on")
            _, missed = drained.result(never)
        finally:
            cell.stop()
    said = text(result)
    assert name is None  # the cell's answer, for both steps
    assert f"{b} IO64 on " in said and f" s after {a} IO128 on" in said
    delay = float(said.split(f"{b} IO64 on ")[1].split(" s after")[0])
    assert 0.0 < delay < 1.0  # robotB answers 0.2 s after robotA, read to within 10 ms
    # Each condition names its robot, and the second's time is that one delay.
    from rac_console.commands.outcome import Outcome

    waits = [f.waited for f in result.feedback if isinstance(f, Outcome) and f.waited]
    assert [w.condition for w in waits] == [f"{a} IO128 on", f"{b} IO64 on"]
    assert f"{waits[1].seconds:.3f}" == f"{delay:.3f}"
    assert "IO65 on: not met within 0.3 s" in text(missed)


def test_a_wait_after_needs_a_cell(sims: list[SimulatorThread]) -> None:
    cell = open_cell(sims[:1])
    drained = CellFront(cell)
    try:
        seq = cell.submit("wait IO 64 on within 1 after @robotB IO 128 on")
        assert "no target named robotB is open here; open: robotA" in text(drained.result(seq)[1])
    finally:
        cell.stop()


async def test_the_repl_asks_a_cells_confirm_question_naming_its_target(
    tmp_path: Path, sims: list[SimulatorThread]
) -> None:
    confirm = Target(
        sims[1].host, sims[1].port, policy=WritePolicy(Writes.CONFIRM), read_only=False
    )
    cell = Cell([("robotA", Target(sims[0].host, sims[0].port)), ("robotB", confirm)])
    driver = Driver(tmp_path, screen=True)
    driver.engine = cell  # type: ignore[assignment]

    async def steps(d: Driver) -> None:
        await d.until(lambda out: "robotA\x1b[0m ›" in out, "the prompt")
        d.type("@robotB put I 10 5\r")
        await d.until(lambda out: "Write I10:" in out, "the confirm question")
        await d.until(lambda out: " on robotB (" in out, "the question naming robotB")
        d.type("n\r")
        await d.until(lambda out: "robotB › PUT I10 not confirmed" in out, "the No, named")

    await driver.run(steps)
    assert sims[1].server.controller.value(I, 10) != 5  # type: ignore[union-attr]
