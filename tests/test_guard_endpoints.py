"""A profile's rules follow its controller however its address is typed: ``127.1``,
``localhost``, ``0x7f000001`` or ``::ffff:127.0.0.1`` are 127.0.0.1, and a profile
written with a name applies to the address typed by hand (issue 19, item 1).

The CLI runs as a subprocess against a recording server on 127.0.0.1 port 0, which
says whether anything reached the wire; ``connect`` is driven through the engine.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rac_console.commands.policy import TargetProfile, WritePolicy, Writes, parse_allow
from rac_console.commands.profiles import match_profile
from rac_console.engine import Engine
from rac_console.session.endpoints import addresses
from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import Front, cli, profile
from tests.support.servers import RecordingServer

#: Every way of typing 127.0.0.1 that the resolver of this machine knows.
FORMS = [
    "127.1",
    "localhost",
    "LOCALHOST",
    "127.0.0.01",
    "127.000.000.001",
    "2130706433",
    "0x7f000001",
    "::ffff:127.0.0.1",
]


def _profiles(policy: WritePolicy, host: str = "127.0.0.1", port: int = 5006) -> dict:
    return {"cell": TargetProfile("cell", host, port, None, None, policy)}


# ---------------------------------------------------------------- pure matching


def test_the_addresses_of_every_form_are_127_0_0_1() -> None:
    for form in FORMS:
        found = addresses(form)
        assert found is not None and "127.0.0.1" in found, form


def test_a_profile_at_the_same_endpoint_matches_however_typed() -> None:
    profiles = _profiles(WritePolicy(Writes.READ_ONLY, None, "profile cell"))
    for form in FORMS:
        assert match_profile(profiles, form, 5006, addresses).profile is profiles["cell"], form
    assert match_profile(profiles, "127.1", 5007, addresses).profile is None  # another port


def test_of_several_profiles_at_one_endpoint_the_strictest_rules() -> None:
    def fake(host: str) -> frozenset[str] | None:
        return frozenset({"10.0.0.3"}) if host in ("robot3.cell", "10.0.0.3") else None

    profiles = {
        "open": TargetProfile("open", "robot3.cell", 5006, None, None, WritePolicy()),
        "ro": TargetProfile("ro", "10.0.0.3", 5006, None, None, WritePolicy(Writes.READ_ONLY)),
    }
    assert match_profile(profiles, "robot3.cell", None, fake).profile is profiles["ro"]


def test_a_profile_whose_host_cannot_be_resolved_is_said_and_matched_by_text() -> None:
    profiles = _profiles(WritePolicy(Writes.READ_ONLY), host="robot9.invalid")
    match = match_profile(profiles, "127.0.0.1", None, addresses)
    assert match.profile is None
    [notice] = match.notices()
    assert "robot9.invalid cannot be resolved" in notice and "cell" in notice
    assert match_profile(profiles, "ROBOT9.invalid", None, addresses).profile is not None


# ------------------------------------------------------------------- the CLI


@pytest.mark.slow
@pytest.mark.parametrize("form", FORMS)
def test_a_read_only_profile_holds_for_its_address_typed_another_way(
    form: str,
    env: dict[str, str],
    config: Callable[[str], Path],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording()
    config(profile("ro", server.port, 'writes = "read-only"'))
    result = cli(env, "-H", form, "-p", str(server.port), "put", "I", "10", "5")
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "read-only" in result.stderr and "profile ro" in result.stderr
    assert bytes(server.received) == b""  # nothing reached the wire


@pytest.mark.slow
def test_confirm_and_allow_hold_for_localhost_and_127_1(
    env: dict[str, str],
    config: Callable[[str], Path],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording()
    config(profile("c", server.port, 'writes = "confirm"\nallow = ["I 100-199"]'))
    for form in ("localhost", "127.1"):
        outside = cli(env, "-H", form, "-p", str(server.port), "put", "I", "10", "5")
        assert outside.returncode == 2 and "allow" in outside.stderr, outside.stderr
        unasked = cli(env, "-H", form, "-p", str(server.port), "put", "I", "100", "5")
        assert unasked.returncode == 2 and "--yes" in unasked.stderr, unasked.stderr
    assert bytes(server.received) == b""


@pytest.mark.slow
def test_a_profile_written_with_a_name_holds_for_the_ip_typed(
    env: dict[str, str],
    config: Callable[[str], Path],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording()
    config(profile("ro", server.port, 'writes = "read-only"', host="localhost"))
    result = cli(env, "-H", "127.0.0.1", "-p", str(server.port), "send", "PUT:RC8:10:I:3,5")
    assert result.returncode == 2, result.stderr
    assert bytes(server.received) == b""


@pytest.mark.slow
def test_read_only_flag_wins_over_an_open_profile_at_the_address(
    env: dict[str, str],
    config: Callable[[str], Path],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording()
    config(profile("open", server.port, 'writes = "open"'))
    result = cli(env, "--read-only", "-H", "127.1", "-p", str(server.port), "put", "I", "1", "2")
    assert result.returncode == 2 and "read-only" in result.stderr
    assert bytes(server.received) == b""


@pytest.mark.slow
def test_an_unresolvable_profile_host_is_said_once(
    env: dict[str, str],
    config: Callable[[str], Path],
) -> None:
    with SimulatorThread() as sim:
        config(profile("far", sim.port, 'writes = "read-only"', host="robot9.invalid"))
        result = cli(env, "-H", "127.0.0.1", "-p", str(sim.port), "get", "I", "1")
    assert result.returncode == 0, result.stderr
    assert result.stderr.count("robot9.invalid cannot be resolved") == 1, result.stderr


# ------------------------------------------------------- connect (console, REPL)


@pytest.fixture
def cell() -> Iterator[SimulatorThread]:
    with SimulatorThread() as simulator:
        yield simulator


@pytest.mark.parametrize("form", ["127.1", "localhost", "0x7f000001"])
def test_connect_to_a_read_only_profiles_address_typed_another_way(
    form: str, cell: SimulatorThread
) -> None:
    profiles = _profiles(WritePolicy(Writes.READ_ONLY, None, "profile cell"), port=cell.port)
    engine = Engine(None, interval=0.05, timeout=1.0, profiles=profiles)
    engine.start()
    try:
        front = Front(engine)
        connected = "\n".join(front.run(f"connect {form}:{cell.port}"))
        assert "read-only" in connected, connected
        refused = "\n".join(front.run("put I 10 5"))
        assert "read-only" in refused and "nothing was sent" in refused, refused
    finally:
        engine.stop()


@pytest.mark.parametrize("form", ["127.1", "LOCALHOST"])
def test_connect_keeps_allow_for_the_address_typed_another_way(
    form: str, cell: SimulatorThread
) -> None:
    policy = WritePolicy(Writes.OPEN, (parse_allow("I 100-199"),), "profile cell")
    engine = Engine(None, interval=0.05, timeout=1.0, profiles=_profiles(policy, port=cell.port))
    engine.start()
    try:
        front = Front(engine)
        front.run(f"connect {form}:{cell.port}")
        refused = "\n".join(front.run("put I 10 5"))
        assert "allow" in refused and "nothing was sent" in refused, refused
    finally:
        engine.stop()
