"""An engine's jobs as its threads share them: submitted from any thread, each with its
number, run one at a time on the engine's thread, cancelled from any thread; and the
answers front ends give to the confirm questions of a write.

Everything else of the engine belongs to its thread alone (see the package docstring);
this is what the other threads may reach, under one lock. The jobs waiting are held in
one queue, which a cancel of the queued jobs reads too (no second copy of them). Loads
nothing of the engine's parts: an engine takes lines before they are made.
"""

from __future__ import annotations

import itertools
import threading
from collections import deque
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ...commands.language import Command
    from ..published.events import Result
    from .job import Job


class Inbox:
    """The jobs submitted and not run yet, the one running, and the confirm answers."""

    def __init__(self, numbers: Iterator[int] | None = None) -> None:
        """``numbers``: where jobs get their numbers (the engines of a cell share one)."""
        self.numbers = numbers if numbers is not None else itertools.count(1)
        self._lock = threading.Condition()
        self._jobs: deque[Job] = deque()  # submitted, not started, in order
        self._stopped = False
        self._running: Job | None = None
        self._answers: dict[int, bool] = {}  # confirm answers, by the job's number

    # ------------------------------------------------------------ any thread

    def put(
        self,
        what: str | Command,
        line: str | None = None,
        seq: int | None = None,
        then: Callable[[Result], None] | None = None,
        publish: bool = True,
        source: str | None = None,
        valid: Callable[[], bool] | None = None,
    ) -> Job:
        """Queue a line or a command (``seq``: the number its cell gave it; ``then``,
        ``publish``, ``source`` and ``valid``: see :class:`~.job.Job`)."""
        from .job import Job

        with self._lock:
            number = next(self.numbers) if seq is None else seq
            job = Job(number, what, line, then, publish, source, valid)
            self._jobs.append(job)
            self._lock.notify()
        return job

    def put_stop(self) -> None:
        """The engine's loop ends when it next asks (the jobs still queued are not run)."""
        with self._lock:
            self._stopped = True
            self._lock.notify()

    def cancel(self, queued: bool = False) -> bool:
        """Cancel the job running (with ``queued``, the ones waiting too); whether one
        was running."""
        with self._lock:
            running = self._running
            cancelled = list(self._jobs) if queued else []
            if running is not None:
                cancelled.append(running)
        for job in cancelled:
            job.cancel()
        return running is not None

    def answer(self, seq: int, yes: bool) -> None:
        with self._lock:
            self._answers[seq] = yes

    def abandon(self) -> list[Job]:
        """Every job queued, taken out unrun: the engine's thread has ended, and a job
        left in the queue would be waited for forever."""
        with self._lock:
            taken = list(self._jobs)
            self._jobs.clear()
        return taken

    # ------------------------------------------------------------ the engine's thread

    def empty(self) -> bool:
        return not self._jobs

    def next(self, wait: float | None) -> Job | tuple[()] | None:
        """The next job, running from now; ``()`` when none came within ``wait`` seconds
        (0: between polls, asked without waiting); None: stop."""
        with self._lock:
            if wait != 0 and not self._jobs and not self._stopped:
                self._lock.wait_for(lambda: self._jobs or self._stopped, timeout=wait)
            if self._stopped:
                return None
            if not self._jobs:
                return ()
            self._running = self._jobs.popleft()
            return self._running

    def end(self) -> None:
        """The job running has ended."""
        with self._lock:
            self._running = None

    def take_answer(self, seq: int) -> bool | None:
        """The answer to the confirm question of job ``seq``, taken (None: none came)."""
        with self._lock:
            return self._answers.pop(seq, None)
