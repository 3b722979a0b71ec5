"""The watch list's schedule: which row is polled next, the cycle figures, the backoff
after a failure, and what a cycle hands to the CSV log and the trends.

Run on the engine's thread between jobs, one row at a time, so a typed command waits
at most for the one poll in flight.

It reads only, and hands the session its request directly (no write gate: it is the hot
path): the one request it sends is a row's :attr:`~..watch.rows.WatchRow.request`, the
row's GET, made and checked a well-formed GET once when the row is first polled. That it
sends nothing else is held by tests/test_write_gate.py (no other request reaches the
session from here) at no cost per poll.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable

from ...commands.language import VarRef
from ...protocol import Variant, describe_hresult, hresult_name
from ...session import BadReply, ConnectFailed, Reply, RequestTimeout, TransportError
from ..published.events import Connection, Cycle, Reading
from ..setup.poll_bounds import UNBOUNDED, PollBounds
from ..watch.csvsink import CsvSink
from ..watch.rows import WatchList, WatchRow
from .link import Link
from .publisher import Publisher
from .schedule import Schedule

#: The status line's polls/s: the GETs of the cycles begun in this many seconds (at
#: least the last cycle), over the time from the first of them to the newest start.
RATE_WINDOW = 2.0


class Poller:
    def __init__(
        self,
        link: Link,
        publisher: Publisher,
        csv: CsvSink,
        *,
        interval: float,
        bounds: PollBounds = UNBOUNDED,
        cycles: bool,
        publish_status: Callable[[bool], None],
        cut_cycles: bool = False,
        max_cycles: int | None = None,
        readings: bool = False,
    ) -> None:
        """``publish_status(force)``: the status now (``force``), or at most every
        tenth of a second while polling flat out. ``cut_cycles``: a cycle ends at its
        first failed exchange (the rest are marked SKIPPED), so a script watching a dead
        controller waits out one timeout a cycle, not one a variable. ``max_cycles``:
        polling pauses after that many cycles (``watch --count N``). ``readings``: each
        Cycle also carries how each read went (the CLI's lines are made of them).
        ``bounds``: the least interval and the most rows it takes (:meth:`set_interval`,
        :meth:`add_rows`); it starts at the floor if ``interval`` is under it."""
        self._link = link
        self._cut_cycles = cut_cycles
        self._keep_readings = cycles and readings
        self._max_cycles = max_cycles
        self.cycles_done = 0
        #: Reads of watched rows by result: ok, error (the controller said no), no reply.
        self.reads = [0, 0, 0]
        self.publish_status = publish_status
        self._publisher = publisher
        self.csv = csv
        self.bounds = bounds
        self.interval = bounds.interval_from(interval)
        self.publish_cycles = cycles
        self.watch = WatchList()
        self.paused = False
        self.seen: frozenset[tuple[str, int]] = frozenset()  # offered by completion
        self.cycle_seconds: float | None = None
        self.polls_per_second: float | None = None
        self._cycle: deque[WatchRow] = deque()  # rows still to poll in this cycle
        self._cycle_started = 0.0  # perf_counter()
        self._cycle_count = 0
        self._samples: list[tuple[VarRef, Variant | None]] = []  # read in this cycle
        self._readings: list[Reading] = []  # and how each read went, for Cycle
        #: (start, polls) of the cycles ended within RATE_WINDOW, oldest first: polls/s.
        self._window: deque[tuple[float, int]] = deque()
        self._window_polls = 0
        self._schedule = Schedule()  # on time.monotonic()

    # ------------------------------------------------------ what commands change

    def see(self, variables: tuple[VarRef, ...] | list[VarRef]) -> None:
        """Indices used or watched, offered by completion."""
        more = {(v.kind.code, v.index) for v in variables} - self.seen
        if more:
            self.seen = self.seen | more

    def set_interval(self, seconds: float) -> None:
        """Poll every ``seconds`` from now on; InputError under the bounds' floor."""
        self.bounds.check_period(seconds, "interval")
        self.interval = seconds
        self.wake()

    def add_rows(self, variables: list[VarRef], label: str, every: float | None) -> int:
        """Watch ``variables`` (see :meth:`..watch.rows.WatchList.add`); InputError, with no
        row added, when ``every`` is under the bounds' floor or the rows pass the cap."""
        if every is not None:
            self.bounds.check_period(every, "every")
        new = len(set(variables) - self.watch.rows.keys())
        self.bounds.check_rows(len(self.watch.rows), new)
        return self.watch.add(variables, label, every)

    def wake(self) -> None:
        """The watch list, interval, pause or target changed: poll (or retry) now."""
        self._schedule.restart()
        if self._link.retry_at is not None:
            self._link.end_retry()
        self._publisher.status_dirty = True

    def set_paused(self, paused: bool) -> None:
        self.paused = paused
        if paused:
            self.forget_figures()
            self._cycle.clear()
        self.wake()

    def forget_figures(self) -> None:
        """Round trips and poll rates measured on a connection that is gone say nothing now."""
        self.cycle_seconds = self.polls_per_second = None
        self._window.clear()
        self._window_polls = 0

    def stop_cycle(self) -> None:
        self._cycle.clear()

    def new_target(self) -> None:
        """Another target: nothing of the last one is shown as its (one CSV file, one
        controller)."""
        for row in self.watch.start_afresh():
            self._publisher.show_row(row)
        ended = self.csv.stop() if self.csv.path is not None else None
        if ended is not None:
            self._publisher.alert(f"CSV log stopped at the change of target: {ended.path}")

    # ------------------------------------------------------------- figures

    @property
    def period(self) -> float:
        """Seconds between poll cycles: the interval, or a row's shorter ``every``."""
        return self.watch.period(self.interval)

    def interval_met(self) -> bool:
        """Period 0 asks for polls back to back: met by definition."""
        period = self.period
        if self.cycle_seconds is None or period == 0:
            return True
        return self.cycle_seconds <= period * 1.05 + 0.001

    # ------------------------------------------------------------ polling

    def wait_time(self) -> float | None:
        """How long the engine may wait for a job before it has a poll to make (None:
        nothing to poll)."""
        if self._link.session is None or self.paused or not self.watch.rows:
            return None
        now = time.monotonic()
        if self._link.retry_at is not None:
            return max(0.0, self._link.retry_at - now)
        if self._cycle:
            return 0
        return self._schedule.wait(now)

    def poll_once(self, more: Callable[[], bool] | None = None) -> None:
        """One step: one row polled, or a cycle begun or ended. With ``more``, the
        cycle's next rows are polled too while it says yes (the engine's inbox is
        empty: a typed command still waits for one poll at most)."""
        link = self._link
        now = time.monotonic()
        if link.retry_at is not None:
            if now < link.retry_at:
                return
            link.end_retry()
        if not self._cycle:
            if self._schedule.wait(now) > 0:
                return
            self._begin_cycle(now)
            if not self._cycle:  # every row has its own, longer period
                return
        row = self._cycle[0]
        if not row.watched:  # unwatched during the cycle
            self._cycle.popleft()
            self._end_cycle_if_done()
            return
        if link.early_drop:
            # The last connection closed before it served a couple of exchanges: wait,
            # then go on with this row (cutting the cycle would starve the rest).
            link.early_drop = False
            served = link.backoff.served
            self._publisher.note(
                f"the connection closed after {served} good exchange{'s' * (served != 1)}: "
                f"waiting {link.backoff.delay:g} s before the next try"
            )
            self._retry("dropped")
            return
        cycle = self._cycle
        cycle.popleft()
        observed = self._publisher.polls_observed()
        try:
            self._poll_row(row, observed)
            self._cycle_count += 1
            while more is not None and cycle and not link.early_drop and more():
                row = cycle.popleft()
                if row.watched:
                    self._poll_row(row, observed)
                    self._cycle_count += 1
        except ConnectFailed as exc:
            self._unreachable(row.var, exc)
            return
        self._end_cycle_if_done()

    def _unreachable(self, var: VarRef, exc: ConnectFailed) -> None:
        link = self._link
        if not link.lost:
            link.lost = True
            for failed in self.watch.mark_all("DISCONNECTED"):
                self._publisher.show_row(failed)
            # A connection that never opened was not lost: say why it cannot open.
            self._publisher.note(f"connection lost: {exc}" if link.ever_connected else str(exc))
        self._cycle.clear()
        if self.csv.path is not None:  # a row per try, its cells empty: no connection
            self.csv.cycle_ended(time.time(), self.watch.rows)
        if self.publish_cycles:  # the cycle ends here: the rest were not read
            self._samples.append((var, None))
            if self._keep_readings:
                self._readings.append((var, exc))
            self._publish_cycle(time.time())
        self._count_cycle()
        link.early_drop = False  # this failure has its own wait
        self._retry("lost" if link.ever_connected else exc.problem)

    def _retry(self, state: Connection) -> None:
        self._link.begin_retry(state)
        if self._link.retry_at is not None:
            self._schedule.not_before(self._link.retry_at)
        self.publish_status(True)

    def _begin_cycle(self, now: float) -> None:
        started = time.perf_counter()
        self._measure_rate(started)
        interval = self.interval
        self._cycle.extend(row for row in self.watch.rows.values() if row.due(now, interval))
        self._cycle_started, self._cycle_count = started, 0
        self._samples, self._readings = [], []
        self._schedule.start(now, self.period)

    def _measure_rate(self, started: float) -> None:
        """polls/s as a cycle starts: the GETs over the last :data:`RATE_WINDOW`
        seconds, not one cycle's. Cycles poll different rows (a row's own ``every``, a
        row polled late in one cycle and due again only in the one after): one cycle's
        count over its period said 5 polls/s for as long as the cycles that polled one
        row were the ones shown, while a hundred went out each second."""
        window = self._window
        while len(window) > 1 and window[0][0] < started - RATE_WINDOW:
            self._window_polls -= window.popleft()[1]
        if window and started > window[0][0] and self._window_polls:
            self.polls_per_second = self._window_polls / (started - window[0][0])

    def _end_cycle_if_done(self) -> None:
        if self._cycle:
            return
        if self._cycle_count:
            self.cycle_seconds = time.perf_counter() - self._cycle_started
            self._window.append((self._cycle_started, self._cycle_count))
            self._window_polls += self._cycle_count
        if self._cycle_count:
            self._cycle_ended()
        self.publish_status(False)  # at most every STATUS_EVERY while polling flat out

    def _poll_row(self, row: WatchRow, observed: bool) -> None:
        """Poll one row; ``observed``: its frames go somewhere (else none is made)."""
        session = self._link.session
        assert session is not None
        outbox = self._publisher.outbox
        if not observed:  # the status line's "waiting for a reply", with no frame to say it
            outbox.waiting_since = time.perf_counter()
        reply: Reply | TransportError
        try:
            reply = session.exchange(row.request, poll=True, observe=observed)
        except ConnectFailed:
            raise
        except TransportError as failure:
            reply = failure
        finally:
            if not observed:
                outbox.waiting_since = None
        if isinstance(reply, TransportError):
            exc = reply
            self.reads[2] += 1
            self._link.mark_failure(exc)
            status = {RequestTimeout: "TIMEOUT", BadReply: "BAD REPLY"}.get(type(exc))
            if row.fail(status or "DISCONNECTED", time.monotonic()):
                self._publisher.show_row(row)
            if self.publish_cycles:
                self._samples.append((row.var, None))
            if self._keep_readings:
                self._readings.append((row.var, exc))
            if self._cut_cycles:
                self._skip_the_rest()
            return
        self._link.backoff.good()
        response = reply.response
        variant = response.variant
        self.reads[0 if response.ok else 1] += 1
        if response.ok and variant is not None:
            changed = row.update(variant, time.monotonic())
        else:
            variant = None
            status = hresult_name(response.code) or describe_hresult(response.code)[:10]
            changed = row.fail(status, time.monotonic())
        if self.publish_cycles:
            self._samples.append((row.var, variant))
        if self._keep_readings:
            self._readings.append((row.var, reply))
        if changed:
            self._publisher.show_row(row)

    def _skip_the_rest(self) -> None:
        now = time.monotonic()
        for skipped in self._cycle:
            if skipped.fail("SKIPPED", now):
                self._publisher.show_row(skipped)
        self._cycle.clear()

    def _cycle_ended(self) -> None:
        """A cycle's values go to the CSV log and the trends (when asked for)."""
        wall = time.time()
        if self.csv.path is not None:
            self.csv.cycle_ended(wall, self.watch.rows)
        if self.publish_cycles:
            self._publish_cycle(wall)
        self._samples = []
        self._count_cycle()

    def _publish_cycle(self, wall: float) -> None:
        samples, readings = tuple(self._samples), tuple(self._readings)
        self._samples, self._readings = [], []
        cycle = Cycle(wall, time.monotonic(), samples, self._link.opened, readings)
        self._publisher.emit(cycle)

    def _count_cycle(self) -> None:
        """A cycle ended, whichever way: after ``max_cycles`` of them polling pauses."""
        self.cycles_done += 1
        if self._max_cycles is not None and self.cycles_done >= self._max_cycles:
            self.paused = True
            self._cycle.clear()

    def poll_until(self, until: float, deadline: float, stopping: Callable[[], bool]) -> None:
        """Until ``time.perf_counter()`` reaches ``until`` (between a job's reads): poll
        the rows that are due, sleep when none is. A poll may take a whole timeout: none
        starts that could end after the job's ``deadline``. ``stopping()`` ends it."""
        while not stopping():
            now = time.perf_counter()
            if now >= until:
                return
            wait = self.wait_time()
            if wait == 0 and deadline - now > self._link.timeout:
                self.poll_once()
                continue
            if wait == 0:
                wait = None  # no time for a poll: sleep to the next read
            remaining = until - now
            time.sleep(remaining if wait is None else min(remaining, wait))
