"""``connect NAME``, ``connect sim`` and ``connect HOST``: the engine takes the profile's
target, label, colour and write rules, or drops them, and its status says which.

A second simulator on 127.0.0.1 port 0 plays the controller a profile names.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from rac_console.commands.language import Connect
from rac_console.commands.policy import TargetProfile, WritePolicy, Writes, parse_allow
from rac_console.engine import Engine
from rac_console.engine.commands.builtin import parse_command
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import Front


@pytest.fixture
def cell() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


def profiles_for(cell: SimulatorThread) -> dict[str, TargetProfile]:
    return {
        "cell3": TargetProfile(
            "cell3",
            cell.host,
            cell.port,
            "Cell 3 — welding",
            "red",
            WritePolicy(Writes.CONFIRM, (parse_allow("I 100-199"),), "profile cell3"),
        ),
        "cell4": TargetProfile(
            "cell4", cell.host, cell.port, None, None, WritePolicy(Writes.READ_ONLY)
        ),
    }


@contextmanager
def started(**options: object) -> Iterator[Front]:
    options.setdefault("timeout", 1.0)
    engine = Engine(None, interval=0.05, **options)  # type: ignore[arg-type]
    engine.start()
    try:
        yield Front(engine)
    finally:
        engine.stop()


def text(front: Front, line: str) -> str:
    return "\n".join(front.run(line))


def test_connect_sim_and_connect_name_parse() -> None:
    assert parse_command("connect sim") == Connect(None, 5006)
    assert parse_command("connect cell3") == Connect("cell3", 5006)
    assert parse_command("connect cell3:6000") == Connect("cell3", 6000, port_given=True)
    assert parse_command("connect sim:5006") == Connect("sim", 5006, port_given=True)


def test_connect_name_takes_the_profile_and_connect_sim_drops_it(cell: SimulatorThread) -> None:
    cell.server.controller.handle(b"PUT:RC8:1:I:3,777")  # before anyone connects
    with started(profiles=profiles_for(cell)) as front:
        front.until(lambda: front.status is not None, "the first status")
        assert front.status is not None and front.status.is_simulator
        assert front.status.writes == "open"
        said = text(front, "connect cell3")
        assert "Cell 3 — welding" in said and f"{cell.host}:{cell.port}" in said
        # cell4 (read-only) names the same controller: the strictest rules apply (issue 30)
        assert "read-only" in said
        status = front.status
        assert status is not None and not status.is_simulator
        assert (status.profile, status.label, status.colour) == ("cell3", "Cell 3 — welding", "red")
        assert (status.writes, status.connection) == ("read-only", "connected")
        assert "777" in text(front, "get I 1")  # reads go to the profile's controller
        said = text(front, "connect sim")
        assert "built-in simulator" in said and "writes open" in said
        status = front.status
        assert status is not None and status.is_simulator
        assert (status.profile, status.label, status.colour, status.writes) == (
            None,
            None,
            None,
            "open",
        )


def test_a_read_only_profile_refuses_puts_and_connect_sim_drops_it(cell: SimulatorThread) -> None:
    with started(profiles=profiles_for(cell)) as front:
        text(front, "connect cell4")
        assert front.status is not None and front.status.writes == "read-only"
        assert "read-only" in text(front, "put I 1 5")
        assert not [f for f in front.frames if f.direction == "tx" and f.data.startswith(b"PUT")]
        text(front, f"connect {cell.host}:{cell.port}")  # its address: still read-only
        assert front.status is not None and front.status.writes == "read-only"
        text(front, "connect sim")
        status = front.status
        assert status is not None and (status.profile, status.writes) == (None, "open")
        assert not status.read_only


def test_read_only_from_the_command_line_stays_through_connect(cell: SimulatorThread) -> None:
    with started(profiles=profiles_for(cell), read_only=True) as front:
        text(front, "connect cell3")
        assert front.status is not None and front.status.writes == "read-only"
        text(front, "connect sim")
        assert front.status is not None and front.status.writes == "read-only"
        assert front.status.read_only


def test_connect_to_a_profiles_address_keeps_its_rules(cell: SimulatorThread) -> None:
    """Typing the address instead of the name must not drop the rules (nor a name in
    another case); two profiles at one address: the stricter one's."""
    found = profiles_for(cell)
    cell3 = found["cell3"]
    with started(profiles=found) as front:
        text(front, f"connect {cell.host}:{cell.port}")
        status = front.status
        assert status is not None and status.profile == "cell4"  # read-only beats confirm
        assert status.read_only
        text(front, "connect sim")
        text(front, "connect CELL3")
        assert front.status is not None and front.status.profile == cell3.name


def test_connect_a_bare_name_that_is_no_profile_says_which_there_are(
    cell: SimulatorThread,
) -> None:
    with started(profiles=profiles_for(cell), timeout=0.5) as front:
        said = text(front, "connect cell5")
        assert "no profile named cell5 (profiles: cell3, cell4)" in said
    with started(timeout=0.5) as front:
        assert "no profile named cell5 (the config file names none)" in text(front, "connect cell5")


def test_connect_name_with_a_port_overrides_the_profiles(cell: SimulatorThread) -> None:
    found = {"cell3": TargetProfile("cell3", cell.host, 1, "Cell 3")}
    with started(profiles=found) as front:
        said = text(front, f"connect cell3:{cell.port}")
        assert front.status is not None and front.status.connection == "connected", said
        assert front.status.label == "Cell 3"
