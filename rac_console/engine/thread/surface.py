"""What a cell and a front end call on an engine: :class:`~.engine.Engine` here, or the
agent's client that stands in for an engine running in the agent
(:class:`rac_console.agent.client.RemoteEngine`)."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from ...commands.language import Command
    from ...commands.policy import TargetProfile
    from ...commands.target import Target
    from ...session import Frame
    from ..commands.registry import Registry
    from ..published.events import Result
    from ..published.outbox import Outbox
    from ..setup.options import EngineOptions
    from ..setup.where import Where


class EngineLike(Protocol):
    """Start it, submit lines, drain :attr:`outbox`, stop it."""

    outbox: Outbox
    options: EngineOptions
    where: Where
    numbers: Iterator[int]
    died: str | None

    @property
    def registry(self) -> Registry: ...

    @property
    def target(self) -> Target: ...

    @property
    def profiles(self) -> Mapping[str, TargetProfile]: ...

    @property
    def ended(self) -> bool: ...

    def start(self, connect: bool = True) -> None: ...

    def submit(self, line: str) -> int: ...

    def submit_command(
        self,
        command: Command | str,
        line: str | None = None,
        seq: int | None = None,
        then: Callable[[Result], None] | None = None,
        publish: bool = True,
    ) -> int: ...

    def stop(self, timeout: float = 5.0) -> None: ...

    def cancel(self, queued: bool = False) -> None: ...

    def answer_confirm(self, seq: int, yes: bool) -> None: ...

    def set_poll_frames(self, shown: bool) -> None: ...

    def add_frame_observer(self, observer: Callable[[Frame], None]) -> None: ...

    def alert(self, text: str) -> None: ...

    def publish_target(self) -> None: ...
