"""Who is told what crosses a session, and what they are told.

A session's frame observers (a log, a recorder, the console's frame view) get each
frame: a request sent, its reply with what the session made of it, a line nobody asked
for, the tail of a line too long, a reply cut short; its state observers each change of
the connection's state; its resend observers why a GET went out again. The frames of a
read are made here from the :class:`~.machine.Verdict` the session's machine gave it.
A frame observer that fails is logged and never breaks the session.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable

from ..protocol import RequestLine
from .machine import Verdict
from .types import Frame, FrameObserver, State, StateObserver

logger = logging.getLogger(__name__)


class Observers:
    """A session's observers: of its frames, of its state, of its resends."""

    __slots__ = ("frames", "resends", "states")

    def __init__(self) -> None:
        self.frames: list[FrameObserver] = []
        self.states: list[StateObserver] = []
        self.resends: list[Callable[[str], None]] = []

    def publish(self, frame: Frame) -> None:
        for observer in self.frames:
            try:
                observer(frame)
            except Exception:  # an observer (a log, a recorder) must never break the session
                logger.exception("frame observer failed")

    def state(self, state: State) -> None:
        for observer in self.states:
            observer(state)

    def resend(self, why: str) -> None:
        for observer in self.resends:
            observer(why)

    def read(
        self,
        verdict: Verdict,
        arrived: float,
        rtt: float,
        poll: bool,
        asked: RequestLine,
        with_answer: bool,
    ) -> None:
        """The frames of the read that ended the wait for the request ``asked``, all
        stamped ``arrived``: the answer (``with_answer``: the request's own frames are
        kept), the lines nobody asked for, then the tail of a line too long (the
        request's, when no answer came before it)."""
        answer = verdict.answer
        if answer is not None and with_answer:
            self.publish(
                Frame(
                    arrived,
                    "rx",
                    answer + b"\r",
                    rtt,
                    poll=poll,
                    response=verdict.response,
                    problem=verdict.problem,
                    request=asked,
                )
            )
        self.strays(verdict.strays, arrived)
        if verdict.too_long is not None:
            unasked = answer is not None  # the reply came: the tail answers nothing
            self.publish(
                Frame(
                    arrived,
                    "rx",
                    verdict.too_long,
                    unsolicited=unasked,
                    request=None if unasked else asked,
                )
            )

    def strays(self, lines: Iterable[bytes], arrived: float | None = None) -> None:
        """Lines nobody asked for (stamped now, unless ``arrived`` says when)."""
        for line in lines:
            stamp = time.time() if arrived is None else arrived
            self.publish(Frame(stamp, "rx", line, unsolicited=True))

    def cut_short(self, fragment: bytes, asked: RequestLine | None) -> None:
        """The start of a reply (to ``asked``, when known) that the connection's end cut
        off: the bytes as they came, with no CR."""
        self.publish(Frame(time.time(), "rx", fragment, request=asked))
