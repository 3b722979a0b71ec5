"""Rules follow the endpoint reached, not the name typed (issue 30, defects 1, 2, 3, 6).

Every test runs the real CLI as a subprocess against fake controllers that record each
line they receive (:class:`servers.RecordingServer`, 127.0.0.1 port 0), and judges a
write from the controller's side: which port received a ``PUT:``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pytest

from rac_console.commands.policy import AllowRange, TargetProfile, WritePolicy, Writes
from rac_console.commands.profiles import parse_config
from rac_console.commands.target import resolve_target
from rac_console.protocol import InputError, kind_of
from tests.support.drivers import cli, profile
from tests.support.servers import RecordingServer

pytestmark = pytest.mark.slow


def puts(server: RecordingServer) -> list[bytes]:
    """The PUT lines a fake controller received."""
    return [line for line in server.lines if line.startswith(b"PUT:")]


Servers = Callable[..., RecordingServer]
Config = Callable[[str], Path]


# ------------------------------------------------------------ a name with another port


@pytest.mark.parametrize(
    "how",
    [
        ["-H", "bench", "-p", "{ro}", "put", "I", "10", "5"],
        ["-H", "bench:{ro}", "put", "I", "10", "5"],
        ["-H", "bench", "-p", "{ro}", "send", "PUT:RC8:10:I:3,5"],
        ["-H", "BENCH:{ro}", "send", "PUT:RC8:10:I:3,5"],
    ],
)
def test_a_profiles_name_with_another_port_gets_the_rules_of_that_port(
    how: list[str],
    env: dict[str, str],
    config: Config,
    recording: Servers,
) -> None:
    bench, ro = recording(), recording()
    config(profile("bench", bench.port) + profile("ro", ro.port, 'writes = "read-only"'))
    words = [w.format(ro=ro.port) for w in how]
    result = cli(env, *words)
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "read-only" in result.stderr and "profile ro" in result.stderr
    assert puts(ro) == [] and puts(bench) == []


def test_a_name_with_another_port_in_run_and_a_cell(
    env: dict[str, str],
    config: Config,
    recording: Servers,
) -> None:
    bench, ro, other = recording(), recording(), recording()
    config(profile("bench", bench.port) + profile("ro", ro.port, 'writes = "read-only"'))
    script = "put I 10 5\nPUT:RC8:10:I:3,5\n"
    run = cli(env, "-H", f"bench:{ro.port}", "run", "--keep-going", "-", stdin=script)
    assert run.returncode == 2, run.stderr
    assert run.stderr.count("read-only") == 2, run.stderr  # each line refused, said why
    cell = cli(env, "-H", f"bench:{ro.port},127.0.0.1:{other.port}", "put", "@ro", "I", "10", "5")
    assert cell.returncode == 2 and "read-only" in cell.stderr, cell.stderr
    assert puts(ro) == [] and puts(bench) == []


# ------------------------------------------------- two profiles at one endpoint


def test_naming_the_lax_of_two_profiles_at_one_endpoint_gets_the_strict_rules(
    env: dict[str, str],
    config: Config,
    recording: Servers,
) -> None:
    ro, other = recording(), recording()
    config(
        profile("ro", ro.port, 'writes = "read-only"')
        + profile("rw2", ro.port, host="localhost")
        + profile("other", other.port)
    )
    alone = cli(env, "-H", "rw2", "put", "I", "10", "5")
    assert alone.returncode == 2 and "read-only" in alone.stderr, alone.stderr
    assert cli(env, "-H", "rw2", "send", "PUT:RC8:10:I:3,5").returncode == 2
    in_cell = cli(env, "-H", "other,rw2", "put", "@rw2", "I", "10", "5")
    assert in_cell.returncode == 2 and "read-only" in in_cell.stderr, in_cell.stderr
    assert puts(ro) == []


def test_the_strictest_of_two_profiles_merges_their_allow_lists() -> None:
    def addresses(host: str) -> frozenset[str] | None:
        return frozenset({"127.0.0.1"}) if host in ("localhost", "127.0.0.1") else None

    io = kind_of("IO")
    parsed = parse_config(
        {
            "target": {
                "a": {"host": "127.0.0.1", "port": 7000, "allow": ["I 100-199", "IO 64-71"]},
                "b": {"host": "localhost", "port": 7000, "writes": "confirm",
                      "allow": ["I 150-250"]},
            }
        },
        "config.toml",
    )  # fmt: skip
    target = resolve_target("a", None, profiles=parsed.profiles, resolve=addresses)
    assert target.policy.writes is Writes.CONFIRM  # b's
    assert target.policy.allow == (AllowRange(kind_of("I"), 150, 199),)  # both allow only these
    assert not any(rule.kind is io for rule in target.policy.allow)


# ------------------------------------------------------------------ names in case


def test_profile_names_that_differ_only_in_case_are_refused_at_load(
    env: dict[str, str],
    config: Config,
    recording: Servers,
) -> None:
    one, two = recording(), recording()
    config(profile("Cell3", one.port) + profile("cell3", two.port))
    result = cli(env, "-H", "cell3", "put", "I", "10", "5")
    assert result.returncode == 2
    [line] = result.stderr.strip().splitlines()
    assert "Cell3" in line and "cell3" in line and "case" in line
    assert puts(one) == [] and puts(two) == []


def test_cell_names_that_differ_only_in_case_are_refused() -> None:
    profiles = {"a": {"host": "h", "port": 1}, "b": {"host": "h", "port": 2}}
    with pytest.raises(InputError, match=r"Line2.*line2|line2.*Line2"):
        parse_config(
            {
                "target": profiles,
                "cell": {"Line2": {"targets": ["a", "b"]}, "line2": {"targets": ["a", "b"]}},
            },
            "config.toml",
        )


def test_a_cells_targets_named_in_another_case_are_one_profile() -> None:
    profiles = {"Cell3": {"host": "h", "port": 1}, "cell4": {"host": "h", "port": 2}}
    with pytest.raises(InputError, match="twice"):
        parse_config(
            {"target": profiles, "cell": {"line": {"targets": ["Cell3", "cell3"]}}},
            "config.toml",
        )
    parsed = parse_config(
        {"target": profiles, "cell": {"line": {"targets": ["CELL3", "Cell4"]}}}, "config.toml"
    )
    assert parsed.cells["line"].targets == ("Cell3", "cell4")  # the profiles' own names


# ------------------------------------------------------- two members at one endpoint


def test_two_members_at_one_endpoint_are_refused(
    env: dict[str, str],
    config: Config,
    recording: Servers,
    tmp_path: Path,
) -> None:
    a = recording()
    config(profile("A", a.port))
    csv = tmp_path / "dup.csv"
    result = cli(
        env, "-H", f"A,127.0.0.1:{a.port}", "watch", "I", "1", "--count", "2",
        "--log-csv", str(csv),
    )  # fmt: skip
    assert result.returncode == 2, (result.stdout, result.stderr)
    [line] = result.stderr.strip().splitlines()
    assert "A" in line and f"127.0.0.1:{a.port}" in line and "one controller" in line
    assert a.lines == []
    localhost = cli(env, "-H", f"localhost:{a.port},A", "get", "@A", "I", "1")
    assert localhost.returncode == 2 and "one controller" in localhost.stderr


def test_a_profile_with_another_port_is_shown_by_the_profile_it_reaches() -> None:
    bench = TargetProfile("bench", "127.0.0.1", 7001)
    ro = TargetProfile("ro", "127.0.0.1", 7002, policy=WritePolicy(Writes.READ_ONLY))
    target = resolve_target("bench", 7002, profiles={"bench": bench, "ro": ro})
    assert target.profile is ro and target.read_only
    assert (target.host, target.port) == ("127.0.0.1", 7002)
    plain = resolve_target("bench", 7003, profiles={"bench": bench, "ro": ro})
    assert plain.profile is bench and not plain.read_only  # no profile names 7003
    locked = replace(bench, policy=WritePolicy(Writes.READ_ONLY, None, "profile bench"))
    elsewhere = resolve_target("bench", 7003, profiles={"bench": locked, "ro": ro})
    assert elsewhere.read_only  # naming a profile never makes its rules laxer
    assert any("bench is 127.0.0.1:7001" in notice for notice in elsewhere.notices)


# ----------------------------------------------------- connect in the console and REPL


def test_connect_a_name_with_another_port_takes_the_rules_of_that_port(
    recording: Servers,
) -> None:
    from rac_console.engine import Engine
    from tests.support.drivers import Front

    bench, ro = recording(), recording()
    profiles = {
        "bench": TargetProfile("bench", "127.0.0.1", bench.port),
        "ro": TargetProfile(
            "ro", "127.0.0.1", ro.port, policy=WritePolicy(Writes.READ_ONLY, None, "profile ro")
        ),
    }
    engine = Engine(None, interval=0.05, timeout=1.0, profiles=profiles)
    engine.start()
    try:
        front = Front(engine)
        said = "\n".join(front.run(f"connect BENCH:{ro.port}"))
        assert "read-only" in said and "profile ro" in said, said
        refused = "\n".join(front.run("put I 10 5") + front.run("send PUT:RC8:10:I:3,5"))
        assert refused.count("read-only") == 2, refused
    finally:
        engine.stop()
    assert puts(ro) == [] and puts(bench) == []
