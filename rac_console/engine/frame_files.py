"""Where frames are written besides the screen: ``--record``/``record`` (JSON lines)
and ``--log``/``transcript`` (plain text), started and stopped while running."""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal

from ..session import Frame
from .recorder import FrameRecorder
from .transcript import FrameTranscript

Kind = Literal["record", "transcript"]


class FrameFiles:
    """The recorder and the transcript of one engine (either may be off)."""

    def __init__(
        self, record: str | None, transcript: str | None, alert: Callable[[str], None]
    ) -> None:
        """Raises InputError when a file cannot be opened (before any thread starts)."""
        self._alert = alert
        self.recorder = FrameRecorder(record, alert) if record else None
        self.transcript = FrameTranscript(transcript, alert) if transcript else None
        #: Why a file that has since been stopped failed: still said in the exit status.
        self._failed: dict[str, str] = {}

    def frame(self, frame: Frame) -> None:
        if self.recorder is not None:
            self.recorder(frame)
        if self.transcript is not None:
            self.transcript(frame)

    def note(self, text: str, when: float) -> None:
        if self.transcript is not None:
            self.transcript.note(text, when)

    def running(self, kind: Kind) -> FrameRecorder | FrameTranscript | None:
        return self.recorder if kind == "record" else self.transcript

    def set(self, kind: Kind, path: str | None) -> None:
        """Start (``path``) or forget (None, closed by the caller) the ``kind`` file;
        raises InputError when it cannot be opened."""
        ended = self.running(kind)
        if ended is not None and ended.failure is not None:
            self._failed[kind] = ended.failure
        if kind == "record":
            self.recorder = FrameRecorder(path, self._alert) if path is not None else None
        else:
            self.transcript = FrameTranscript(path, self._alert) if path is not None else None

    def failure(self, kind: Kind) -> str | None:
        running = self.running(kind)
        return (running.failure if running is not None else None) or self._failed.get(kind)

    def path(self, kind: Kind) -> str | None:
        running = self.running(kind)
        return running.path if running is not None else None

    def close(self) -> None:
        for running in (self.recorder, self.transcript):
            if running is not None:
                running.close()
