"""The engine: the target, the one session, the watch list and its poller, on one thread.

See the package docstring for the thread rules. Lines come in through :meth:`submit`
(any thread) and are run one at a time, in order, between polls: a typed command waits
at most for the one poll in flight. Everything else goes out through the outbox.
"""

from __future__ import annotations

import itertools
import queue
import threading
import time
from collections import deque
from collections.abc import Mapping

from ..commands.check import check_pointer
from ..commands.language import Command, VarRef
from ..commands.policy import TargetProfile, WritePolicy, Writes
from ..protocol import Variant, describe_hresult, hresult_name
from ..session import (
    BadReply,
    ConnectFailed,
    Disconnected,
    Frame,
    RequestTimeout,
    Session,
    State,
    TransportError,
)
from ..sim.thread import SimulatorThread
from .backoff import Backoff
from .csvsink import CsvSink
from .events import Alert, ConfirmWrite, Cycle, Event, Message, Note, Result, Status
from .outbox import Outbox
from .recorder import FrameRecorder
from .transcript import FrameTranscript
from .watch import WatchList, WatchRow

DEFAULT_INTERVAL = 0.5
SIMULATOR_NOTICE = "no -H given: talking to the built-in RC8 simulator, not a controller"
#: The status is published at most this often while polling flat out (and on every change
#: a user causes).
STATUS_EVERY = 0.1
#: Events are handed to the outbox in batches at least this often while polling (and at
#: once when the engine goes idle or answers a line): one lock per batch, not per frame.
EVENTS_EVERY = 0.01
#: How often an idle engine (nothing to poll) looks whether its connection still lives.
LINK_CHECK_EVERY = 1.0
#: How often a write waiting for its confirmation looks for the answer (polling between).
CONFIRM_CHECK_EVERY = 0.02


class Engine:
    """Start it, submit lines, drain :attr:`outbox`, stop it."""

    def __init__(
        self,
        host: str | None = None,
        port: int = 5006,
        *,
        timeout: float = 2.0,
        read_only: bool = False,
        record: str | None = None,
        transcript: str | None = None,
        interval: float = DEFAULT_INTERVAL,
        outbox: Outbox | None = None,
        cycles: bool = False,
        log_csv: str | None = None,
        policy: WritePolicy | None = None,
        verify: bool = True,
        profile: TargetProfile | None = None,
        profiles: Mapping[str, TargetProfile] | None = None,
    ) -> None:
        """Raises InputError when ``record`` or ``transcript`` (``--log``) cannot be opened
        (before any thread starts).

        With ``cycles``, a :class:`Cycle` event follows each poll cycle (for trends).
        ``log_csv`` starts a CSV log at the first poll cycle (raises InputError when the
        file cannot be written). ``policy`` is what writes the target allows (a profile's
        ``writes`` and ``allow``); ``verify`` reads every PUT back; ``profile`` names the
        target (its host and port are ``host`` and ``port``); ``profiles`` are the ones
        ``connect NAME`` knows."""
        self.outbox = outbox if outbox is not None else Outbox()
        self._target = (host, port)
        self.timeout = timeout
        self.policy = policy if policy is not None else WritePolicy()
        # --read-only, kept through connect; a read-only profile's policy adds its own.
        self.base_read_only = read_only
        self.read_only = read_only or self.policy.writes is Writes.READ_ONLY
        # What ``connect HOST`` (no profile) and the command line allow.
        self.base_policy = self.policy if profile is None else WritePolicy()
        self.verify = verify
        self.profile = profile
        self.profiles: Mapping[str, TargetProfile] = profiles or {}
        self.current_seq = 0  # the submitted line running now (a confirm names it)
        self.target_id = 0  # counts the targets opened: a front end forgets the last one's
        self._answers: dict[int, bool] = {}  # confirm answers, by seq (any thread writes)
        self._answers_lock = threading.Lock()
        self.interval = interval
        self.watch = WatchList()
        self.seen: set[tuple[str, int]] = set()
        self._seen_frozen: frozenset[tuple[str, int]] = frozenset()
        self.paused = False
        self.session: Session | None = None
        self.simulator: SimulatorThread | None = None
        self.host: str | None = None
        self.port = port
        self.connection: str = "closed"
        self.ever_connected = False  # on this target: "not connected yet" until it has
        self.retry_at: float | None = None
        self.cycle_seconds: float | None = None
        self.polls_per_second: float | None = None
        self.backoff = Backoff()
        self.recorder = FrameRecorder(record, self.alert) if record else None
        # --log FILE: the plain-text transcript, with the notes (InputError as record).
        self.transcript = FrameTranscript(transcript, self.alert) if transcript else None
        self.csv = CsvSink(self.alert, self._csv_changed)
        #: Why a record or transcript file that has since been stopped failed.
        self._files_failed: dict[str, str] = {}
        if log_csv:
            self.csv.wait_for_rows(log_csv)
        self._lost = False
        self._early_drop = False
        self._cycle: deque[WatchRow] = deque()  # rows still to poll in this cycle
        self._cycle_started = 0.0  # perf_counter()
        self._cycle_count = 0
        self.publish_cycles = cycles
        self._samples: list[tuple[VarRef, Variant | None]] = []  # read in this cycle
        self._last_cycle: tuple[float, int] | None = None  # start, polls: for polls/s
        self._next_cycle_at = 0.0  # monotonic()
        self._status_at = 0.0
        self._status_dirty = True
        self._events: list[Event] = []  # published at the next flush_events()
        self._events_at = 0.0  # perf_counter() of the last flush
        self._inbox: queue.SimpleQueue[tuple[int, str | Command] | None] = queue.SimpleQueue()
        self._seq = itertools.count(1)
        self._seq_lock = threading.Lock()
        self._last_seq = 0  # the last line or command submitted
        self.skip_through = 0  # lines submitted up to this one were cancelled: not run
        self._connect_first = True
        self._started = threading.Event()
        self._stopping = threading.Event()
        self._cancelled = threading.Event()  # the command running now was cancelled
        self._thread = threading.Thread(target=self._run, name="rac-engine", daemon=True)

    # ------------------------------------------------------- any thread

    def start(self, connect: bool = True) -> None:
        """Open the target (the simulator starts here when no host was given) and, with
        ``connect``, the connection; returns once the first status is in the outbox."""
        self._connect_first = connect
        self._thread.start()
        self._started.wait(15)

    def submit(self, line: str) -> int:
        """Queue a typed line; its :class:`Result` comes out with the number returned."""
        with self._seq_lock:
            seq = self._last_seq = next(self._seq)
        self._inbox.put((seq, line))
        return seq

    def submit_command(self, command: Command) -> int:
        """Queue a command a front end made itself (F2's pause, the REPL's end of a
        live watch): run like a typed line, with no line to echo."""
        with self._seq_lock:
            seq = self._last_seq = next(self._seq)
        self._inbox.put((seq, command))
        return seq

    def stop(self, timeout: float = 5.0) -> None:
        """End the thread: a request in flight is cut short, the target closed."""
        if not self._thread.is_alive():
            return
        self._stopping.set()  # lines still queued are not run; a latency run ends
        self._inbox.put(None)  # stop
        session = self.session
        if session is not None:
            session.interrupt()
        self._thread.join(timeout)

    def cancel(self, queued: bool = False) -> None:
        """Cut short the command running now (Ctrl-C at the REPL): a request in flight
        fails at once, a latency run or a wait ends; polling goes on. With ``queued``
        (Esc in the console), the lines submitted so far behind it are not run either:
        a write typed during a long wait must not go out once the user said stop."""
        if queued:
            with self._seq_lock:
                self.skip_through = self._last_seq
        self._cancelled.set()
        session = self.session
        if session is not None:
            session.cancel()

    def answer_confirm(self, seq: int, yes: bool) -> None:
        """A front end's answer to a :class:`ConfirmWrite` (any thread)."""
        with self._answers_lock:
            self._answers[seq] = yes

    @property
    def stopping(self) -> bool:
        """True once :meth:`stop` or :meth:`cancel` was called: a latency run ends early."""
        return self._stopping.is_set() or self._cancelled.is_set()

    def begin_command(self) -> None:
        """A new line starts: a cancel meant for the one before is forgotten."""
        self._cancelled.clear()

    def connect_failed(self, error: ConnectFailed | None = None) -> None:
        """A typed command found the controller unreachable: that was no early drop of a
        connection (none was made), so the poller marks none; the status line says why
        (refused, unreachable, …) rather than a state that looks quiet and healthy."""
        self._early_drop = False
        if error is not None:
            self.connection = error.problem
            self._status_dirty = True

    # ---------------------------------------------------- engine thread

    def _run(self) -> None:
        from .handlers import handle

        try:
            self.open_target(*self._target)
            self.publish_status(force=True)
            self._started.set()
            if self._connect_first:
                self._connect_at_start()
            while not self._stopping.is_set():
                wait = self._wait_time()
                idle = wait is None and self.connection == "connected"
                if wait != 0:
                    self.flush_events()
                    if self._status_dirty:
                        self.publish_status(force=True)
                item = self._next(LINK_CHECK_EVERY if idle else wait)
                if item is None:
                    break  # stop
                if item:
                    handle(self, *item)
                    continue
                if idle:
                    self._check_idle_link()
                    continue
                self._poll_once()
        except Exception as exc:  # a bug must not leave the front end waiting in silence
            self.alert(f"the engine stopped on an internal error: {exc!r}")
        finally:
            self._started.set()
            self.close_target()
            if self.recorder is not None:
                self.recorder.close()
            if self.transcript is not None:
                self.transcript.close()
            self.csv.stop()
            self.flush_events()
            self.publish_status(force=True)

    def _next(self, wait: float | None) -> tuple[int, str | Command] | tuple[()] | None:
        """The next line or command; ``()`` when none came in time; None: stop."""
        try:
            if wait == 0:  # between polls: ask without raising when nothing came
                return self._inbox.get_nowait() if not self._inbox.empty() else ()
            return self._inbox.get(timeout=wait)
        except queue.Empty:
            return ()

    def set_frame_file(self, kind: str, path: str | None) -> None:
        """Start (``path``) or forget (None, closed by the caller) the ``record`` or
        ``transcript`` file; raises InputError when it cannot be opened."""
        ended = self.recorder if kind == "record" else self.transcript
        if ended is not None and ended.failure is not None:  # still said in the exit status
            self._files_failed[kind] = ended.failure
        if kind == "record":
            self.recorder = FrameRecorder(path, self.alert) if path is not None else None
        else:
            self.transcript = FrameTranscript(path, self.alert) if path is not None else None
        self._status_dirty = True

    def _check_idle_link(self) -> None:
        """Nothing polled, nothing typed: a connection that died in the quiet (the
        controller closed it, keepalive gave up on it) is shown now, not at the next
        command."""
        session = self.session
        reason = session.check_idle() if session is not None else None
        if reason is not None:
            self._lost = True  # "reconnected" is said when the next command gets through
            self.connection = "lost"  # not "closed": that reads as a quiet, healthy target
            self._status_dirty = True
            # An alert, not a note: the REPL prints it without frames on, at once.
            self.alert(f"connection lost while idle: {reason}; the next command reconnects")

    def _connect_at_start(self) -> None:
        """Open the connection at start, so the status line tells the truth at once."""
        if self.session is None:
            return
        try:
            self.session.connect()
        except (ConnectFailed, Disconnected) as exc:
            if isinstance(exc, ConnectFailed):
                self.connect_failed(exc)
            retry = f"{exc}: commands will retry {check_pointer(self.host, self.port)}"
            self.emit(Result(0, (Message(retry, "error"),)))
            self.flush_events()

    # ------------------------------------------------------------ target

    def open_target(self, host: str | None, port: int) -> None:
        if host is None:
            self.simulator = SimulatorThread().start()
            host, port = self.simulator.host, self.simulator.port
        self.host, self.port = host, port
        self.target_id += 1
        if self.target_id > 1:  # another target: nothing of the last one is shown as its
            for row in self.watch.start_afresh():
                self.show_row(row)
            ended = self.csv.stop() if self.csv.path is not None else None
            if ended is not None:  # one file, one controller
                self.alert(f"CSV log stopped at the change of target: {ended.path}")
        self.backoff, self._early_drop, self._lost = Backoff(), False, False
        self.ever_connected = False
        session = Session(host, port, timeout=self.timeout)
        session.add_frame_observer(self._on_frame)
        session.add_state_observer(self._on_state)
        session.add_resend_observer(self._on_resend)
        self.session = session
        self.wake()

    def close_target(self) -> None:
        if self.session is not None:
            self.session.close()
            self.session = None
        if self.simulator is not None:
            self.simulator.stop()
            self.simulator = None
        self.connection = "closed"
        self.retry_at = None
        self._cycle.clear()
        self._forget_figures()

    @property
    def target(self) -> str:
        if self.session is None:
            return "NOT CONNECTED"
        if self.simulator is not None:
            return "SIMULATOR (built-in)"
        return f"LIVE {self.host}:{self.port}"

    # ------------------------------------------------------------ events

    def emit(self, event: Event) -> None:
        """Queue an event for the outbox (handed over by :meth:`flush_events`)."""
        self._events.append(event)

    def flush_events(self) -> None:
        if self._events:
            self.outbox.put_many(self._events)
            self._events = []
        self._events_at = time.perf_counter()

    def _on_frame(self, frame: Frame) -> None:
        if self.recorder is not None:
            self.recorder(frame)
        if self.transcript is not None:
            self.transcript(frame)
        self._events.append(frame)
        # The request in flight, for the status line's "waiting for a reply": set as a
        # request leaves, cleared by its reply or by the connection's end.
        self.outbox.waiting_since = time.perf_counter() if frame.direction == "tx" else None
        if time.perf_counter() - self._events_at > EVENTS_EVERY:
            self.flush_events()  # while polling, and during a long command (latency)

    def note(self, text: str) -> None:
        now = time.time()
        if self.transcript is not None:
            self.transcript.note(text, now)
        self.emit(Note(text, now))

    def alert(self, text: str) -> None:
        if self.transcript is not None:
            self.transcript.note(text)
        self.emit(Alert(text))
        self.flush_events()

    def show_row(self, row: WatchRow) -> None:
        self.outbox.put_row(row.view())

    def see(self, variables: tuple[VarRef, ...] | list[VarRef]) -> None:
        """Indices used or watched, offered by completion."""
        before = len(self.seen)
        self.seen.update((v.kind.code, v.index) for v in variables)
        if len(self.seen) != before:
            self._seen_frozen = frozenset(self.seen)

    def _on_state(self, state: State) -> None:
        self.connection = state
        if state != "connected":
            self.outbox.waiting_since = None
            self._forget_figures()
        if state == "closed" and self.backoff.closed():
            self._early_drop = True  # the poller waits before its next request
        if state in ("connecting", "connected"):  # closed while connecting counts too
            self.backoff.connected()
            self.retry_at = None
            if state == "connected":
                self.ever_connected = True
            if state == "connected" and self._lost:
                self._lost = False
                self.note(f"reconnected to {self.host}:{self.port}")
        self._status_dirty = True
        if state == "connecting":
            # A connect can block for a whole timeout: the line must not say "connected"
            # meanwhile, so the change is published now, not when the loop next idles.
            self.publish_status(force=True)
            self.flush_events()

    def _on_resend(self, reason: str) -> None:
        """A GET found its connection dead and went again on a fresh one: marked in the
        log, so the request seen twice there is explained."""
        self.note(f"{reason}: the GET was sent again on a fresh connection")

    def _forget_figures(self) -> None:
        """Round trips and poll rates measured on a connection that is gone say nothing now."""
        self.cycle_seconds = self.polls_per_second = None
        self._last_cycle = None
        if self.session is not None:
            self.session.last_rtt = None

    def mark_failure(self, error: TransportError) -> None:
        """One line in the log for each request that got no trustworthy reply."""
        if isinstance(error, ConnectFailed):
            return  # an outage is marked once, by the poller or the command's own result
        if isinstance(error, Disconnected):
            self.note(f"{error}: the next request reconnects")
        else:
            self.note(f"{error}: session reset")

    def publish_status(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self._status_at < STATUS_EVERY:
            self._status_dirty = True
            return
        self._status_at, self._status_dirty = now, False
        session = self.session
        period = self.period
        self.outbox.put_status(
            Status(
                target=self.target,
                is_simulator=self.simulator is not None,
                has_session=session is not None,
                host=self.host,
                port=self.port,
                timeout=self.timeout,
                read_only=self.read_only,
                connection=self.connection,
                retry_at=self.retry_at,
                rtt=session.last_rtt if session is not None else None,
                paused=self.paused,
                watched=len(self.watch.rows),
                interval=self.interval,
                period=period,
                cycle_seconds=self.cycle_seconds,
                polls_per_second=self.polls_per_second,
                interval_met=self._interval_met(period),
                record_failure=(self.recorder.failure if self.recorder is not None else None)
                or self._files_failed.get("record"),
                transcript_failure=(
                    self.transcript.failure if self.transcript is not None else None
                )
                or self._files_failed.get("transcript"),
                csv_log=self.csv.path,
                csv_failure=self.csv.failure,
                seen=self._seen_frozen,
                profile=self.profile.name if self.profile is not None else None,
                label=self.profile.label if self.profile is not None else None,
                colour=self.profile.colour if self.profile is not None else None,
                writes="read-only" if self.read_only else self.policy.writes.value,
                verify=self.verify,
                target_id=self.target_id,
                ever_connected=self.ever_connected,
                recording=self.recorder.path if self.recorder is not None else None,
                transcribing=self.transcript.path if self.transcript is not None else None,
            )
        )

    # ------------------------------------------------------------ polling

    @property
    def period(self) -> float:
        """Seconds between poll cycles: the interval, or a row's shorter ``every``."""
        return self.watch.period(self.interval)

    def _interval_met(self, period: float) -> bool:
        """Period 0 asks for polls back to back: met by definition."""
        if self.cycle_seconds is None or period == 0:
            return True
        return self.cycle_seconds <= period * 1.05 + 0.001

    def wake(self) -> None:
        """The watch list, interval, pause or target changed: poll (or retry) now."""
        self._next_cycle_at = 0.0
        if self.retry_at is not None:
            self._end_retry()
        self._status_dirty = True

    def set_paused(self, paused: bool) -> None:
        self.paused = paused
        if paused:
            self.cycle_seconds = self.polls_per_second = None
            self._last_cycle = None
            self._cycle.clear()
        self.wake()

    def _wait_time(self) -> float | None:
        """How long the loop may wait for a line before it has a poll to make (None:
        nothing to poll, wait for a line)."""
        if self.session is None or self.paused or not self.watch.rows:
            return None
        now = time.monotonic()
        if self.retry_at is not None:
            return max(0.0, self.retry_at - now)
        if self._cycle:
            return 0
        return max(0.0, self._next_cycle_at - now)

    def _poll_once(self) -> None:
        """One step of the poller: one row polled, or a cycle begun or ended."""
        now = time.monotonic()
        if self.retry_at is not None:
            if now < self.retry_at:
                return
            self._end_retry()
        if not self._cycle:
            if now < self._next_cycle_at:
                return
            self._begin_cycle(now)
            if not self._cycle:  # every row has its own, longer period
                self._next_cycle_at = now + self.period
                return
        row = self._cycle[0]
        if not row.watched:  # unwatched during the cycle
            self._cycle.popleft()
            self._end_cycle_if_done()
            return
        if self._early_drop:
            # The last connection closed before it served a couple of exchanges: wait,
            # then go on with this row (cutting the cycle would starve the rest).
            self._early_drop = False
            served = self.backoff.served
            self.note(
                f"the connection closed after {served} good exchange{'s' * (served != 1)}: "
                f"waiting {self.backoff.delay:g} s before the next try"
            )
            self._begin_retry("dropped")
            return
        self._cycle.popleft()
        try:
            self._poll_row(row)
        except ConnectFailed as exc:
            if not self._lost:
                self._lost = True
                for failed in self.watch.mark_all("DISCONNECTED"):
                    self.show_row(failed)
                # A connection that never opened was not lost: say why it cannot open.
                self.note(f"connection lost: {exc}" if self.ever_connected else str(exc))
            self._cycle.clear()
            if self.csv.path is not None:  # a row per try, its cells empty: no connection
                self.csv.cycle_ended(time.time(), self.watch.rows)
            self._early_drop = False  # this failure has its own wait
            self._begin_retry("lost" if self.ever_connected else exc.problem)
            return
        self._cycle_count += 1
        self._end_cycle_if_done()

    def _begin_cycle(self, now: float) -> None:
        started = time.perf_counter()
        if self._last_cycle is not None:
            last_start, last_count = self._last_cycle
            if last_count and started > last_start:
                self.polls_per_second = last_count / (started - last_start)
        interval = self.interval
        self._cycle.extend(row for row in self.watch.rows.values() if row.due(now, interval))
        self._cycle_started, self._cycle_count = started, 0
        self._samples = []
        self._next_cycle_at = now + self.period

    def _end_cycle_if_done(self) -> None:
        if self._cycle:
            return
        if self._cycle_count:
            self.cycle_seconds = time.perf_counter() - self._cycle_started
            self._last_cycle = (self._cycle_started, self._cycle_count)
        if self._samples:
            self._cycle_ended(tuple(self._samples))
            self._samples = []
        self.publish_status()

    def _poll_row(self, row: WatchRow) -> None:
        session = self.session
        assert session is not None
        try:
            reply = session.exchange(row.request, poll=True)
        except ConnectFailed:
            raise
        except TransportError as exc:
            self.mark_failure(exc)
            status = {RequestTimeout: "TIMEOUT", BadReply: "BAD REPLY"}.get(type(exc))
            if row.fail(status or "DISCONNECTED", time.monotonic()):
                self.show_row(row)
            self._samples.append((row.var, None))
            return
        self.backoff.good()
        response = reply.response
        variant = response.variant
        if response.ok and variant is not None:
            changed = row.update(variant, time.monotonic())
        else:
            variant = None
            status = hresult_name(response.code) or describe_hresult(response.code)[:10]
            changed = row.fail(status, time.monotonic())
        self._samples.append((row.var, variant))
        if changed:
            self.show_row(row)

    def ask_confirm(self, question: ConfirmWrite) -> bool:
        """Publish the question and keep polling until the front end answers; a cancel
        (Esc, Ctrl-C) or a stop is a No."""
        with self._answers_lock:
            self._answers.pop(question.seq, None)
        if self.stopping:  # cancelled already: no question about a write that ended
            return False
        self.emit(question)
        self.publish_status(force=True)
        self.flush_events()
        while not self.stopping:
            with self._answers_lock:
                answer = self._answers.pop(question.seq, None)
            if answer is not None:
                return answer
            self.poll_until(time.perf_counter() + CONFIRM_CHECK_EVERY, float("inf"))
            self.flush_events()
        return False

    def poll_until(self, until: float, deadline: float) -> None:
        """Until ``time.perf_counter()`` reaches ``until`` (between a wait's reads): poll
        the watched rows that are due, sleep when none is. A poll may take a whole
        timeout: none starts that could end after the wait's ``deadline``."""
        while not self.stopping:
            now = time.perf_counter()
            if now >= until:
                return
            wait = self._wait_time()
            if wait == 0 and deadline - now > self.timeout:
                self._poll_once()
                continue
            if wait == 0:
                wait = None  # no time for a poll: sleep to the next read
            remaining = until - now
            time.sleep(remaining if wait is None else min(remaining, wait))

    def _cycle_ended(self, samples: tuple[tuple[VarRef, Variant | None], ...]) -> None:
        """A cycle's values go to the CSV log and the trends (when asked for)."""
        wall = time.time()
        if self.csv.path is not None:
            self.csv.cycle_ended(wall, self.watch.rows)
        if self.publish_cycles:
            self.emit(Cycle(wall, time.monotonic(), samples, self.target_id))

    def _csv_changed(self) -> None:
        self.publish_status(force=True)

    def _begin_retry(self, state: str) -> None:
        """Back off before the next try; the status line counts it down."""
        self.connection = state
        self.retry_at = time.monotonic() + self.backoff.next_delay()
        self.publish_status(force=True)

    def _end_retry(self) -> None:
        self.retry_at = None
        self.connection = self.session.state if self.session is not None else "closed"
        self._status_dirty = True
