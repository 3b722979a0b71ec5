"""``rac.cell``: several controllers from a script, lines routed by ``@NAME`` as the
console routes them. Judged at fake controllers: which one received what."""

from __future__ import annotations

from pathlib import Path

import pytest

import rac_console as rac
from tests.support.drivers import profile
from tests.support.servers import Memory, RecordingServer

HOST = "127.0.0.1"


def _cell_config(tmp_path: Path, first: RecordingServer, second: RecordingServer) -> Path:
    path = tmp_path / "cell.toml"
    path.write_text(
        profile("robot1", first.port)
        + profile("robot2", second.port, 'writes = "read-only"')
        + '[cell.line2]\ntargets = ["robot1", "robot2"]\n',
        encoding="utf-8",
    )
    return path


def test_lines_go_where_the_console_sends_them(recording, tmp_path: Path) -> None:
    first, second = recording(Memory()), recording(Memory())
    config = _cell_config(tmp_path, first, second)
    with rac.cell("LINE2", config=config) as cell:
        assert list(cell) == ["robot1", "robot2"] and cell.current == "robot1"
        assert cell.run("@ROBOT1 put I 10 5") == rac.Written("I10", 5, 10, 5, True)
        assert cell.run("get I 11") == 11  # the current target
        assert cell.run("@robot2 get I 12") == 12
        assert cell.run("# a comment") is None
        cell.use("robot2")
        assert cell.run("send GET:RC8:13:I:") == rac.Sent(13, 0, "0,3,13")
        assert cell["Robot1"].get("I", 14) == 14
    assert first.lines == [
        b"GET:RC8:10:I:",
        b"PUT:RC8:10:I:3,5",
        b"GET:RC8:10:I:",
        b"GET:RC8:11:I:",
        b"GET:RC8:14:I:",
    ]
    assert second.lines == [b"GET:RC8:12:I:", b"GET:RC8:13:I:"]


def test_each_target_keeps_its_own_rules_and_a_refusal_sends_nothing(
    recording, tmp_path: Path
) -> None:
    first, second = recording(Memory()), recording(Memory())
    config = _cell_config(tmp_path, first, second)
    with rac.cell(["robot1", "robot2"], config=config) as cell:
        assert cell["robot2"].writes == "read-only" and cell["robot1"].writes == "open"
        with pytest.raises(rac.Refused, match="profile robot2 is read-only"):
            cell.run("@robot2 put I 10 5")
        with pytest.raises(rac.Refused, match="no target named robot3 is open here"):
            cell.run("@robot3 get I 1")
        for line in (
            "watch I 1",
            "wait I 1 == 1",
            "@robot1 wait I 1 == 1 after @robot2 I 2 == 2",
            "latency 3",
        ):
            with pytest.raises(rac.Refused, match="runs get, put, send"):
                cell.run(line)
        with pytest.raises(KeyError, match="robot3"):
            cell["robot3"]
    assert first.lines == [] and second.lines == []


def test_a_cell_of_addresses_and_one_that_names_a_controller_twice(recording) -> None:
    server, other = recording(Memory()), recording(Memory())
    with rac.cell([f"{HOST}:{server.port}", f"localhost:{other.port}"]) as cell:
        assert cell.names == (f"{HOST}:{server.port}", f"localhost:{other.port}")
        assert cell.run(f"@localhost:{other.port} get I 2") == 2
    with pytest.raises(rac.Refused, match="are one controller"):
        rac.cell([f"{HOST}:{server.port}", f"localhost:{server.port}"])
    with pytest.raises(rac.Refused, match="no cell named nowhere"):
        rac.cell("nowhere")
    assert other.lines == [b"GET:RC8:2:I:"] and server.lines == []


def test_the_demo_cell_is_the_console_s_simulators() -> None:
    with rac.cell("demo") as cell:
        assert cell.names == ("robotA", "robotB")
        cell.run("@robotB put I 10 5")
        assert cell["robotb"].get("I", 10) == 5 and cell["robotA"].get("I", 10) != 5


def test_a_name_the_cell_does_not_hold_or_a_cell_that_is_no_cell_is_a_rac_error(
    recording,
) -> None:
    """``except rac.RacError`` catches every mistake a script can make with a cell: a
    target it does not hold (also a KeyError, as a mapping's) and a cell named by
    something that is neither a name nor a list of targets."""
    server = recording(Memory())
    with rac.cell([f"{HOST}:{server.port}"]) as cell:
        with pytest.raises(rac.RacError) as unknown:
            cell["robotC"]
        assert isinstance(unknown.value, rac.UnknownTarget | KeyError)
        assert str(unknown.value) == (
            f"no target named 'robotC' in this cell; it holds {HOST}:{server.port}"
        )
    for wrong in (5, None, b"line2", [5]):
        with pytest.raises(rac.Refused, match=r"a cell is a \[cell\.NAME\]'s name or a list"):
            rac.cell(wrong)  # type: ignore[arg-type]
    assert server.lines == []
