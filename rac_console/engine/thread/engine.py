"""The engine: one target, its session, its watch list and poller, on one thread.

See the package docstring for the thread rules. Jobs (typed lines, or commands a
front end made) come in through :meth:`Engine.submit` from any thread and run one at
a time, in order, between polls (:mod:`.inbox` holds them); everything else goes out
through the outbox. The engine itself only schedules: the parts are the link
(:mod:`..polling.link`), the poller (:mod:`..polling.poller`), the frame files and the
publisher, every command is run by its registry entry's handler (:mod:`..commands.jobs`)
with a context over the parts (:mod:`.engine_context`), and the status is read out of
them (:mod:`.readout`).
Engines share no mutable state: several run side by side in one process, one per
controller.

The parts (and the commands) are made when the engine starts, on the thread that starts
it, or when first needed: the console makes its engine before its first paint, which
must not wait for them. Files named in the options are opened at once, so that one
that cannot be opened is said before anything starts.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from ...commands.target import Target
from ..published.outbox import Outbox
from ..published.status import Status, described, status_before_start
from ..setup.options import EngineOptions, options_of, target_of
from ..setup.where import UNLISTED_SIMULATOR, Where
from .inbox import Inbox
from .readout import status_of

if TYPE_CHECKING:
    from ...commands.language import Command
    from ...commands.policy import TargetProfile
    from ...session import Frame
    from ..commands.registry import Registry
    from ..files.frame_files import FrameFiles
    from ..polling.link import Link
    from ..polling.plant_tap import PlantTap
    from ..polling.poller import Poller
    from ..polling.publisher import Publisher
    from ..published.events import Feedback, Result
    from ..watch.cellcsv import CellCsv
    from ..watch.csvsink import CsvSink
    from .engine_context import EngineParts
    from .job import Job

SIMULATOR_NOTICE = "no -H given: talking to the built-in RC8 simulator, not a controller"
#: The status is published at most this often while polling flat out (and on every change
#: a user causes).
STATUS_EVERY = 0.1
#: How often an idle engine (nothing to poll) looks whether its connection still lives.
LINK_CHECK_EVERY = 1.0
NOT_RUN = "not run: cancelled (Esc, Ctrl+C) before it started"
#: What a line submitted to an engine whose thread has ended is answered.
ENGINE_STOPPED = "not run: this target's engine has stopped (restart rac-console)"
#: What the line running when the engine died is answered: a write may have gone out.
DIED_RUNNING = "the engine stopped on an internal error while running this: its outcome is unknown"


@dataclass(frozen=True)
class CellFiles:
    """What a cell's member writes to: the cell's files, each line naming the member.
    The cell owns them (opens, closes, says a failure once); the member's options name
    no file."""

    name: str
    files: FrameFiles  # the cell's, seen as this member (FrameFiles.view)
    csv: CellCsv


class Engine:
    """Start it, submit lines, drain :attr:`outbox`, stop it."""

    def __init__(
        self,
        host: str | None = None,
        port: int = 5006,
        *,
        target: Target | None = None,
        options: EngineOptions | None = None,
        outbox: Outbox | None = None,
        where: Where = Where.CONSOLE,
        registry: Registry | None = None,
        numbers: Iterator[int] | None = None,
        cell_files: CellFiles | None = None,
        **words: object,
    ) -> None:
        """The target is ``target``, or made of ``host``, ``port`` and the words
        ``read_only``, ``policy``, ``profile``, ``profiles``; the options are ``options``
        or the words ``timeout``, ``interval``, ``verify``, ``cycles``, ``record``,
        ``transcript``, ``log_csv``. Raises InputError when a file cannot be opened
        (before any thread starts). ``numbers`` gives submitted jobs their numbers:
        the engines of a cell share one, so a number names one job in the cell, and
        ``cell_files`` gives each the cell's files in place of its own."""
        self._rules, self._plain_policy = target_of(host, port, target, words)
        self.options = options if options is not None else options_of(words)
        self.outbox = outbox if outbox is not None else Outbox()
        self.where, self._registry = where, registry
        self._cell_files = cell_files
        self._inbox = Inbox(numbers)
        #: Where submitted jobs get their numbers (shared by the engines of a cell).
        self.numbers = self._inbox.numbers
        self._status_at = 0.0
        self._connect_first = True
        self._started = threading.Event()
        self._stopping = threading.Event()
        #: Why the thread ended without being stopped (an internal error), once it has.
        self.died: str | None = None
        self._thread = threading.Thread(target=self._run, name="rac-engine", daemon=True)
        self._build_lock = threading.Lock()
        self._built = False
        options = self.options
        if options.record or options.transcript or options.log_csv:
            self._build()  # a file that cannot be opened: InputError now, nothing started

    def _build(self) -> None:
        """Make the parts, once (any thread; the first caller makes them)."""
        with self._build_lock:
            if self._built:
                return
            from ..files.frame_files import FrameFiles
            from ..polling.link import Link
            from ..polling.poller import Poller
            from ..polling.publisher import Publisher
            from ..watch.csvsink import CsvSink
            from .engine_context import EngineParts

            options, cell_files = self.options, self._cell_files
            self._files: FrameFiles = (
                cell_files.files
                if cell_files is not None
                else FrameFiles(options.record, options.transcript, self._alert)
            )
            self._publisher: Publisher = Publisher(self.outbox, self._files, options.frames)
            self._csv: CsvSink = CsvSink(
                self._alert,
                lambda: self.publish_status(force=True),
                (cell_files.csv, cell_files.name) if cell_files is not None else None,
            )
            self._link: Link = Link(
                self._publisher,
                options.timeout,
                went_down=self._went_down,
                connecting=self._connecting,
                unlisted_simulator=self.where in UNLISTED_SIMULATOR,
                sessions=options.sessions,
            )
            self._poller: Poller = Poller(
                self._link,
                self._publisher,
                self._csv,
                interval=options.interval,
                bounds=options.bounds,
                cycles=options.cycles,
                publish_status=self.publish_status,
                cut_cycles=options.cut_cycles,
                max_cycles=options.max_cycles,
                readings=options.readings,
            )
            self._parts: EngineParts = EngineParts(
                self._link, self._poller, self._publisher, self._files, self._csv,
                self._switch_target, self._plain_policy, self._plant, self._inbox.take_answer,
                lambda: self.publish_status(force=True),
            )  # fmt: skip
            self._built = True
            if options.log_csv:
                self._csv.wait_for_rows(options.log_csv)

    @property
    def registry(self) -> Registry:
        """The commands this engine runs: the built-in ones unless others were given."""
        if self._registry is None:
            from ..commands.builtin import BUILTIN

            self._registry = BUILTIN
        return self._registry

    # ------------------------------------------------------- any thread

    @property
    def target(self) -> Target:
        """The target open now (``connect`` changes it)."""
        return self._rules

    @property
    def profiles(self) -> Mapping[str, TargetProfile]:
        """The profiles ``connect NAME`` knows (read before the engine starts)."""
        return self._rules.profiles

    def start(self, connect: bool = True) -> None:
        """Open the target (the simulator starts here when no host was given) and, with
        ``connect``, the connection; returns once the first status is in the outbox."""
        self._connect_first = connect
        self._build()
        self._thread.start()
        self._started.wait(15)

    def submit(self, line: str) -> int:
        """Queue a typed line; its :class:`Result` comes out with the number returned."""
        seq = self._inbox.put(line).seq
        self._answer_if_dead()
        return seq

    def submit_command(
        self,
        command: Command | str,
        line: str | None = None,
        seq: int | None = None,
        then: Callable[[Result], None] | None = None,
        publish: bool = True,
        source: str | None = None,
        valid: Callable[[], bool] | None = None,
    ) -> int:
        """Queue a command a front end made itself (F2's pause, Space on an IO row):
        run like a typed line, never parsed; ``line`` is how it is shown (the echo,
        the result), or None for nothing to echo. ``seq``: the number its cell gave
        the line (else the next of :attr:`numbers`). ``then`` is handed its Result on
        this engine's thread once it is out (``publish``: in the outbox; else to
        ``then`` alone), even when the job is not run; ``source``, ``valid``: see Job."""
        seq = self._inbox.put(command, line, seq, then, publish, source, valid).seq
        self._answer_if_dead()
        return seq

    @property
    def ended(self) -> bool:
        """The thread has ended without :meth:`stop` (it died): nothing runs any more."""
        return (
            self._thread.ident is not None
            and not self._thread.is_alive()
            and (not self._stopping.is_set())
        )

    def _answer_if_dead(self) -> None:
        """Once the thread has died, every job queued is answered at once: not run."""
        if self.died is None and not self.ended:
            return
        from ..published.events import Message, Result

        for job in self._inbox.abandon():
            result = Result(job.seq, (Message(ENGINE_STOPPED, "error"),), job.line, None)
            if job.publish:
                self.outbox.put(result)
            if job.then is not None:
                job.then(result)

    def stop(self, timeout: float = 5.0) -> None:
        """End the thread: a request in flight is cut short, the target closed."""
        if not self._thread.is_alive():
            return
        self._stopping.set()  # jobs still queued are not run; a latency run ends
        self._inbox.put_stop()
        session = self._link.session
        if session is not None:
            session.interrupt()
        self._thread.join(timeout)

    def cancel(self, queued: bool = False) -> None:
        """Cut short the job running now (Ctrl-C at the REPL): a request in flight
        fails at once, a latency run or a wait ends; polling goes on. With ``queued``
        (Esc in the console), the jobs submitted so far behind it are not run either:
        a write typed during a long wait must not go out once the user said stop."""
        if not self._inbox.cancel(queued):
            return  # nothing in flight (nor, before the start, any part to reach)
        session = self._link.session
        if session is not None:
            session.cancel()

    def answer_confirm(self, seq: int, yes: bool) -> None:
        """A front end's answer to a :class:`ConfirmWrite` (any thread)."""
        self._inbox.answer(seq, yes)

    def set_poll_frames(self, shown: bool) -> None:
        """Whether the front end shows poll frames (any thread). When nobody shows,
        records or observes them, a poll builds no frame at all."""
        self._build()
        self._publisher.poll_frames = shown

    def add_frame_observer(self, observer: Callable[[Frame], None]) -> None:
        """Call ``observer`` on the engine's thread with every frame, before it is
        published (a sink of one's own; from the next frame on: keep it quick)."""
        self._build()
        self._publisher.observers.append(observer)

    def alert(self, text: str) -> None:
        """Said at once (before start: a notice the front end shows first)."""
        self._build()
        self._alert(text)

    # ---------------------------------------------------- engine thread

    def _alert(self, text: str) -> None:
        self._publisher.alert(text)

    def _run(self) -> None:
        try:
            self._link.open(self._rules)
            self._open_plant()
            self._poller.wake()
            self.publish_status(force=True)
            self._started.set()
            if self._connect_first:
                self._connect_at_start()
            while not self._stopping.is_set():
                wait = self._poller.wait_time()
                idle = wait is None and self._link.connection == "connected"
                if wait != 0:
                    self._publisher.flush()
                    if self._publisher.status_dirty:
                        self.publish_status(force=True)
                else:  # polling flat out: rows, cycles and notes still go out in batches
                    self._publisher.flush_due()
                item = self._inbox.next(LINK_CHECK_EVERY if idle else wait)
                if item is None:
                    break  # stop
                if item:
                    self._run_job(item)
                elif idle:
                    self._link.check_idle()
                else:
                    self._poller.poll_once(more=self._inbox.empty)
        except BaseException as exc:  # a bug must not leave the front end waiting in silence
            if not self._stopping.is_set():
                self.died = f"{type(exc).__name__}: {exc}"
            self._alert(f"the engine stopped on an internal error: {exc!r}")
        finally:
            self._started.set()
            self._link.close()
            self._files.close()
            self._csv.close()
            self._publisher.flush()  # the last rows reach the plant's feed too
            self.publish_status(force=True)
            if self._publisher.tap is not None:
                self._publisher.tap.close()
            if self.died is not None:
                self._answer_if_dead()

    def _run_job(self, job: Job) -> None:
        """Run one job; the status, then its Result, go to the outbox (so a front end
        showing the result knows the state it left)."""
        from ..commands.jobs import run_job
        from ..published.events import Message, Result
        from .engine_context import EngineContext

        self._publisher.source = job.source
        try:
            feedback: list[Feedback]
            if job.cancelled():
                command, feedback = self._parsed(job.what), [Message(NOT_RUN, "error")]
            else:
                context = EngineContext(
                    job,
                    self._parts,
                    self.registry,
                    self._rules,
                    self.options.verify,
                    self._stopping.is_set,
                )
                command, feedback = run_job(self.registry, context, job.what, self.where, job.line)
        except BaseException:  # the thread ends (see _run): this line is answered first
            said = Message(DIED_RUNNING, "error")
            self._answer(job, Result(job.seq, (said,), job.line, self._parsed(job.what)))
            raise
        finally:
            self._inbox.end()
            self._publisher.source = None
        self.publish_status(force=True)
        self._answer(job, Result(job.seq, tuple(feedback), job.line, command))

    def _answer(self, job: Job, result: Result) -> None:
        """A job's Result out: to the outbox after the frames and the status before it,
        then to whoever waits on it (a cell's next line starts there)."""
        if job.publish:
            self._publisher.emit(result)
        self._publisher.flush()
        if job.then is not None:
            job.then(result)

    def _parsed(self, what: str | Command) -> Command | None:
        """The command a job names (None when its line does not parse)."""
        from ...protocol.errors import InputError

        if not isinstance(what, str):
            return what
        try:
            return self.registry.parse(what)
        except InputError:
            return None

    def _connect_at_start(self) -> None:
        from ...commands.check import check_pointer
        from ...session import ConnectFailed, Disconnected
        from ..published.events import Message, Result

        try:
            self._link.connect_at_start()
        except (ConnectFailed, Disconnected) as exc:
            retry = f"{exc}: commands will retry {check_pointer(self._link.host, self._link.port)}"
            self._publisher.emit(Result(0, (Message(retry, "error"),)))
            self._publisher.flush()

    def _switch_target(self, target: Target | None) -> None:
        """``connect`` (another target and its rules) or ``disconnect`` (None)."""
        self._link.close()
        self._poller.stop_cycle()
        if target is None:
            return
        self._rules = target
        self._link.open(target)
        if self._link.opened > 1:
            self._poller.new_target()
        self._poller.wake()
        if self._publisher.tap is not None:  # its values go under its own name
            from ..polling.plant_tap import name_of

            said = self._publisher.tap.rename(name_of(self.options, target))
            if said is not None:
                self._alert_plant(said)

    def _plant(self) -> PlantTap:
        """This engine's feed to the plant, made on first use (``publish``)."""
        from ..polling.plant_tap import open_tap

        if self._publisher.tap is None:
            self._publisher.tap = open_tap(
                self.options, self._rules, self._alert_plant, self._plant_changed,
                (self.submit_command, lambda: self._rules),
            )  # fmt: skip
        return self._publisher.tap

    def _open_plant(self) -> None:
        """Publishing from the start, and --metrics (see
        :func:`..polling.plant_tap.open_at_start`)."""
        from ..polling.plant_tap import open_at_start

        open_at_start(self.options, self._rules, self._plant, self._alert_plant)

    def _plant_changed(self) -> None:
        """The broker's state changed (paho's thread): the status line says so when the
        engine's loop next turns."""
        self._publisher.status_dirty = True

    def _alert_plant(self, text: str) -> None:
        """The plant's news (any thread): said at once, not a failure of the reads."""
        from ..published.events import Alert

        self.outbox.put(Alert(text, local_failure=False))

    def _went_down(self) -> None:
        self._poller.forget_figures()

    def _connecting(self) -> None:
        self.publish_status(force=True)
        self._publisher.flush()

    def publish_status(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self._status_at < STATUS_EVERY:
            self._publisher.status_dirty = True
            return
        self._status_at, self._publisher.status_dirty = now, False
        status = self._status()
        if self._built and self._publisher.tap is not None:
            self._publisher.tap.status(status)
        self.outbox.put_status(status)

    def publish_target(self) -> None:
        """Before :meth:`start`: publish the status of the target about to be opened,
        "connecting…", so a front end can paint the truth while the engine (and the
        built-in simulator) starts; the engine's own first status replaces it."""
        host, port = self._rules.host, self._rules.port
        self.outbox.put_status(
            replace(
                self._status(),
                target=described(host, port),
                is_simulator=host is None,
                has_session=True,
                host=host,
                port=port,
                connection="connecting",
            )
        )

    def _status(self) -> Status:
        if self.died is not None:  # never "connected" once nothing polls any more
            return replace(self._live_status(), connection="engine stopped", has_session=False)
        return self._live_status()

    def _live_status(self) -> Status:
        if not self._built:
            return status_before_start(self._rules, self.options)
        tap = self._publisher.tap
        return status_of(
            self._link, self._poller, self._files, self._csv, self._rules, self.options,
            broker=tap.broker_state if tap is not None else None,
        )  # fmt: skip
