"""An engine's jobs as its threads share them: submitted from any thread, each with its
number, run one at a time on the engine's thread, cancelled from any thread; and the
answers front ends give to the confirm questions of a write.

Everything else of the engine belongs to its thread alone (see the package docstring);
this is what the other threads may reach, each piece under the one lock. Loads nothing
of the engine's parts: an engine takes lines before they are made.
"""

from __future__ import annotations

import itertools
import queue
import threading
from collections.abc import Iterator
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ...commands.language import Command
    from .job import Job


class Inbox:
    """The jobs submitted and not run yet, the one running, and the confirm answers."""

    def __init__(self, numbers: Iterator[int] | None = None) -> None:
        """``numbers``: where jobs get their numbers (the engines of a cell share one)."""
        self.numbers = numbers if numbers is not None else itertools.count(1)
        self._jobs: queue.SimpleQueue[Job | None] = queue.SimpleQueue()  # None: stop
        self._lock = threading.Lock()
        self._queued: dict[int, Job] = {}  # submitted, not started
        self._running: Job | None = None
        self._answers: dict[int, bool] = {}  # confirm answers, by the job's number

    # ------------------------------------------------------------ any thread

    def put(self, what: str | Command, line: str | None = None, seq: int | None = None) -> int:
        """Queue a line or a command (``seq``: the number its cell gave it); its number."""
        from .job import Job

        with self._lock:
            job = Job(next(self.numbers) if seq is None else seq, what, line)
            self._queued[job.seq] = job
        self._jobs.put(job)
        return job.seq

    def put_stop(self) -> None:
        """The engine's loop ends when it takes this (the jobs behind it are not run)."""
        self._jobs.put(None)

    def cancel(self, queued: bool = False) -> bool:
        """Cancel the job running (with ``queued``, the ones waiting too); whether one
        was running."""
        with self._lock:
            running = self._running
            cancelled = list(self._queued.values()) if queued else []
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
        taken: list[Job] = []
        with self._lock:
            while True:
                try:
                    job = self._jobs.get_nowait()
                except queue.Empty:
                    break
                if job is not None:
                    self._queued.pop(job.seq, None)
                    taken.append(job)
        return taken

    # ------------------------------------------------------------ the engine's thread

    def empty(self) -> bool:
        return self._jobs.empty()

    def next(self, wait: float | None) -> Job | tuple[()] | None:
        """The next job; ``()`` when none came within ``wait`` seconds; None: stop."""
        try:
            if wait == 0:  # between polls: ask without raising when nothing came
                return self._jobs.get_nowait() if not self._jobs.empty() else ()
            return self._jobs.get(timeout=wait)
        except queue.Empty:
            return ()

    def begin(self, job: Job) -> None:
        """``job`` runs now."""
        with self._lock:
            self._queued.pop(job.seq, None)
            self._running = job

    def end(self) -> None:
        """The job running has ended."""
        with self._lock:
            self._running = None

    def take_answer(self, seq: int) -> bool | None:
        """The answer to the confirm question of job ``seq``, taken (None: none came)."""
        with self._lock:
            return self._answers.pop(seq, None)
