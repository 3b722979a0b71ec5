"""The status of a running engine, read out of its parts on the engine's thread.

Apart from :mod:`..published.status` (the snapshot itself, and the status before the parts are
made), which the console loads before its first paint and the parts' modules import.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..published.status import Status

if TYPE_CHECKING:
    from ...commands.target import Target
    from ..files.frame_files import FrameFiles
    from ..polling.link import Link
    from ..polling.poller import Poller
    from ..setup.options import EngineOptions
    from ..watch.csvsink import CsvSink


def status_of(
    link: Link,
    poller: Poller,
    files: FrameFiles,
    csv: CsvSink,
    rules: Target,
    options: EngineOptions,
    broker: str | None,
) -> Status:
    """What the status line says of a running engine: its parts as they stand."""
    session = link.session
    profile = rules.profile
    return Status(
        target=link.described,
        is_simulator=link.simulator is not None,
        has_session=session is not None,
        host=link.host,
        port=link.port,
        timeout=link.timeout,
        read_only=rules.read_only,
        connection=link.connection,
        retry_at=link.retry_at,
        rtt=session.last_rtt if session is not None else None,
        paused=poller.paused,
        watched=len(poller.watch.rows),
        interval=poller.interval,
        period=poller.period,
        cycle_seconds=poller.cycle_seconds,
        polls_per_second=poller.polls_per_second,
        interval_met=poller.interval_met(),
        record_failure=files.failure("record"),
        transcript_failure=files.failure("transcript"),
        csv_log=csv.path,
        csv_failure=csv.failure,
        seen=poller.seen,
        profile=profile.name if profile is not None else None,
        label=profile.label if profile is not None else None,
        colour=profile.colour if profile is not None else None,
        writes=rules.writes,
        verify=options.verify,
        target_id=link.opened,
        ever_connected=link.ever_connected,
        recording=files.path("record"),
        transcribing=files.path("transcript"),
        reads=(poller.reads[0], poller.reads[1], poller.reads[2]),
        broker=broker,
    )
