"""Where frames are written besides the screen: ``--record``/``record`` (JSON lines)
and ``--log``/``transcript`` (plain text), started and stopped while running.

An engine alone owns its files. A cell's engines share one pair: the cell makes one
:class:`FrameFiles` and hands each member a view of it (:meth:`FrameFiles.view`) that
names the member in every line. A view starts and stops the shared files (``record
FILE`` typed at any target records them all) and never closes them: the cell does,
once every member has stopped. The files lock each write, as the members write from
their own threads.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Literal

from ...protocol import InputError
from ...protocol.text import terminal_safe
from ...session import Frame
from .recorder import FrameRecorder
from .transcript import FrameTranscript

Kind = Literal["record", "transcript"]


class _Open:
    """The files themselves: one set per engine, or one per cell shared by its views."""

    def __init__(self, alert: Callable[[str], None]) -> None:
        self.alert = alert
        self.lock = threading.Lock()  # a start and a stop from two members' threads
        self.recorder: FrameRecorder | None = None
        self.transcript: FrameTranscript | None = None
        #: Why a file that has since been stopped failed: still said in the exit status.
        self.failed: dict[str, str] = {}


class FrameFiles:
    """The recorder and the transcript of one engine (either may be off), or a cell
    member's view of the cell's (``name`` set: each line names it)."""

    def __init__(
        self, record: str | None, transcript: str | None, alert: Callable[[str], None]
    ) -> None:
        """Raises InputError when a file cannot be opened (before any thread starts)."""
        self._open = _Open(alert)
        self._open.recorder = FrameRecorder(record, alert) if record else None
        try:
            self._open.transcript = FrameTranscript(transcript, alert) if transcript else None
        except InputError:
            if self._open.recorder is not None:
                self._open.recorder.close()
            raise
        self.name: str | None = None
        self.place: int | None = None
        self._owner = True

    def view(self, name: str, place: int | None = None) -> FrameFiles:
        """A member's view: the same files, each line naming ``name`` (and recording
        its ``place`` in the cell, 1 the first: a replay serves the targets in that
        order); closed by us."""
        view = FrameFiles.__new__(FrameFiles)
        view._open, view.name, view._owner = self._open, name, False
        view.place = place
        return view

    @property
    def shared(self) -> bool:
        """Whether these are a cell's files (started and stopped for every target)."""
        return self.name is not None

    @property
    def recorder(self) -> FrameRecorder | None:
        return self._open.recorder

    @property
    def transcript(self) -> FrameTranscript | None:
        return self._open.transcript

    def frame(self, frame: Frame) -> None:
        recorder, transcript = self._open.recorder, self._open.transcript
        if recorder is not None:
            recorder(frame, self.name, self.place)
        if transcript is not None:
            transcript(frame, self.name)

    def note(self, text: str, when: float) -> None:
        transcript = self._open.transcript
        if transcript is not None:
            transcript.note(text, when, self.name)

    def running(self, kind: Kind) -> FrameRecorder | FrameTranscript | None:
        return self._open.recorder if kind == "record" else self._open.transcript

    def set(self, kind: Kind, path: str | None) -> None:
        """Start (``path``) or forget (None, closed by the caller) the ``kind`` file;
        raises InputError when it cannot be opened, or (a cell's, started from another
        target meanwhile) runs already."""
        opened = self._open
        with opened.lock:
            ended = self.running(kind)
            if path is not None and ended is not None:
                raise InputError(f"{kind} already goes to {terminal_safe(ended.path)}")
            if ended is not None and ended.failure is not None:
                opened.failed[kind] = ended.failure
            if kind == "record":
                opened.recorder = FrameRecorder(path, opened.alert) if path is not None else None
            else:
                made = FrameTranscript(path, opened.alert) if path is not None else None
                opened.transcript = made

    def failure(self, kind: Kind) -> str | None:
        running = self.running(kind)
        return (running.failure if running is not None else None) or self._open.failed.get(kind)

    def path(self, kind: Kind) -> str | None:
        running = self.running(kind)
        return running.path if running is not None else None

    def close(self) -> None:
        """Close the files (a view leaves them to the cell that owns them)."""
        if not self._owner:
            return
        for running in (self._open.recorder, self._open.transcript):
            if running is not None:
                running.close()
