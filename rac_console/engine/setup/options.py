"""What an engine is made with: how it runs (:class:`EngineOptions`), and its target
and options when given as words (the tests' and the front ends' way of saying them).

Apart from the engine, which loads with them (see :mod:`..thread.engine`): a front end makes its
options before it makes an engine.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ...commands.plant import NO_CREDENTIALS, Credentials, MqttAddress
from ...commands.policy import TargetProfile, WritePolicy, Writes
from ...commands.target import Target
from .poll_bounds import UNBOUNDED, PollBounds

if TYPE_CHECKING:
    from ...plant.metrics import MetricsBoard
    from ...plant.opcua_server import OpcUaServer
    from ...session import Session

DEFAULT_INTERVAL = 0.5


@dataclass(frozen=True)
class EngineOptions:
    """How an engine runs, besides its target."""

    timeout: float = 2.0
    interval: float = DEFAULT_INTERVAL
    verify: bool = True  # every PUT is read back
    cycles: bool = False  # publish a Cycle after each poll cycle (the console's trends)
    record: str | None = None  # --record FILE
    transcript: str | None = None  # --log FILE
    log_csv: str | None = None  # a CSV log from the first poll cycle
    frames: bool = True  # publish every frame (the CLI's watch shows none)
    cut_cycles: bool = False  # a poll cycle ends at its first failed exchange (the CLI)
    max_cycles: int | None = None  # polling pauses after this many cycles (--count N)
    readings: bool = False  # each Cycle carries how each read went (the CLI's lines)
    #: The plant: the broker the watched values go to from the start (--mqtt, a cell's or
    #: a profile's publish), who we are to it, the --metrics board, and the target's name
    #: in topics and labels (None: the profile's name, or the host).
    publish: MqttAddress | None = None
    credentials: Credentials = NO_CREDENTIALS
    metrics: MetricsBoard | None = None
    opcua: OpcUaServer | None = None  # --opcua: the server the watched values are served by
    plant_name: str | None = None
    #: How much polling may be asked of the controller (a served console's bounds).
    bounds: PollBounds = UNBOUNDED
    #: Makes the session to a host (host, port, timeout): the agent's shared ones.
    sessions: Callable[[str, int, float], Session] | None = None


_TARGET_WORDS = ("read_only", "policy", "profile", "profiles")


def target_of(
    host: str | None, port: int, target: Target | None, words: dict[str, object]
) -> tuple[Target, WritePolicy]:
    """The engine's first target and what ``connect HOST`` (no profile) allows."""
    given = {name: words.pop(name) for name in _TARGET_WORDS if name in words}
    if target is not None:
        return target, target.policy if target.profile is None else WritePolicy()
    read_only = bool(given.get("read_only", False))
    policy = given.get("policy") or WritePolicy()
    profile = given.get("profile")
    profiles = given.get("profiles") or {}
    assert isinstance(policy, WritePolicy)
    assert profile is None or isinstance(profile, TargetProfile)
    assert isinstance(profiles, Mapping)
    target = Target(
        host,
        port,
        profile,
        policy,
        read_only=read_only or policy.writes is Writes.READ_ONLY,
        read_only_flag=read_only,
        profiles=profiles,
    )
    return target, policy if profile is None else WritePolicy()


def options_of(words: dict[str, object]) -> EngineOptions:
    """The options given as words (the tests' and the front ends' way of saying them)."""
    known = set(EngineOptions.__dataclass_fields__)
    unknown = set(words) - known
    if unknown:
        raise TypeError(f"Engine got unexpected words: {', '.join(sorted(unknown))}")
    return EngineOptions(**words)  # type: ignore[arg-type]
