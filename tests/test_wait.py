"""``wait VAR OP VALUE [within SECONDS]``: the parser, the engine behind the console and
the REPL, and ``run`` scripts, against the real simulator."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.commands.conditions import holds, parse_wait
from rac_console.commands.language import Op, Put
from rac_console.commands.outcome import ExitStatus, Outcome
from rac_console.engine import Engine
from rac_console.engine.commands.builtin import parse_command
from rac_console.protocol import InputError, Variant
from rac_console.session import Session
from tests.support.drivers import Front

# ------------------------------------------------------------------ parser


@pytest.mark.parametrize(
    ("line", "op", "within"),
    [
        ("wait IO 128 on within 2", Op.ON, 2.0),
        ("wait IO128 off", Op.OFF, 10.0),
        ("wait I 10 >= 100 within 30", Op.GE, 30.0),
        ("wait I[10] < -5 within 0.5s", Op.LT, 0.5),
        ("wait P 0 changes within 5", Op.CHANGES, 5.0),
        ("wait F 1 = 0.5", Op.EQ, 10.0),
        ('wait S 1 != "part OK" within 1', Op.NE, 1.0),
        ("wait P 1 == 350 0 450 180 0 180 5", Op.EQ, 10.0),
    ],
)
def test_wait_lines_parse(line: str, op: Op, within: float) -> None:
    command = parse_command(line)
    assert command is not None and command.op is op and command.within == within  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("rest", "says"),
    [
        ("I 1", "needs a condition"),
        ("I 1 on", "on and off are for IO"),
        ("S 1 > 3", "compares numbers"),
        ("P 0 >= 3", "compares numbers"),
        ("I 1 >= abc", "needs one number"),
        ("I 1 >= nan", "needs one number"),
        ("I 1 >=", "needs a value"),
        ("I 1 about 3", "unknown condition"),
        ("I 1 >= 5 within 9999", "within must be from 0 to 3600"),
        ("I 1 >= 5 within soon", "within needs a number"),
        ("P 1 == 1 2 3", "P needs 7 values"),
        ("IO 1 == maybe", "IO needs on or off"),
    ],
)
def test_wait_refuses_what_it_cannot_check(rest: str, says: str) -> None:
    with pytest.raises(InputError, match=says):
        parse_wait(rest)


def test_conditions_compare_values_as_read() -> None:
    at_least = parse_wait("I 1 >= 100")
    assert holds(at_least, Variant(3, 100), None)
    assert not holds(at_least, Variant(3, 99), None)
    assert not holds(at_least, Variant(8, "100"), None)  # a string is not a number
    on = parse_wait("IO 5 on")
    assert holds(on, Variant(11, True), None) and not holds(on, Variant(11, False), None)
    changes = parse_wait("P 0 changes")
    first = Variant(8196, [1.0] * 7)
    assert not holds(changes, first, None)
    assert not holds(changes, Variant(8196, [1.0] * 7), first)
    assert holds(changes, Variant(8196, [1.0] * 6 + [2.0]), first)
    assert holds(parse_wait("F 1 == 0.1"), Variant(4, 0.1), None)


# ------------------------------------------------------------------ engine


def run_outcome(front: Front, line: str) -> Outcome:
    seq = front.engine.submit(line)
    front.until(lambda: seq in front.results, f"the answer to {line!r}")
    (outcome,) = front.results[seq].feedback
    assert isinstance(outcome, Outcome)
    return outcome


def test_a_condition_that_holds_is_met_at_the_first_read(front: Front) -> None:
    outcome = run_outcome(front, "wait IO 128 on within 2")  # ON in the simulator
    assert outcome.ok and outcome.waited is not None
    assert outcome.waited.met and outcome.waited.reads == 1
    assert outcome.to_json()["wait"]["condition"] == "IO128 on"


def test_a_condition_never_met_times_out_as_an_error(front: Front) -> None:
    outcome = run_outcome(front, "wait I 1 >= 100 within 0.3")  # I1 is 1
    assert outcome.status == ExitStatus.CONTROLLER_ERROR
    assert outcome.waited is not None and not outcome.waited.met
    assert outcome.waited.reads > 1 and outcome.waited.seconds >= 0.3
    assert "I1 >= 100: not met within 0.3 s" in (outcome.error or "")
    reads = [f for f in front.sent() if f == b"GET:RC8:1:I:\r"]
    assert len(reads) == outcome.waited.reads  # every read on the wire, no more


def test_a_write_from_another_client_ends_the_wait(front: Front) -> None:
    front.until(lambda: front.status is not None and front.status.host is not None, "status")
    assert front.status is not None and front.status.host is not None
    host, port = front.status.host, front.status.port
    seq = front.engine.submit("wait I 20 == 7 within 8")
    front.until(lambda: b"GET:RC8:20:I:\r" in front.sent(), "the wait's first read")
    other = Session(host, port, timeout=2.0)
    try:
        put = parse_command("put I 20 7")
        assert isinstance(put, Put)
        other.exchange(put.request)
    finally:
        other.close()
    front.until(lambda: seq in front.results, "the wait's end")
    (outcome,) = front.results[seq].feedback
    assert isinstance(outcome, Outcome) and outcome.ok
    assert outcome.variant == Variant(3, 7)
    assert outcome.waited is not None and outcome.waited.met and outcome.waited.reads > 1


def test_a_moving_position_changes(front: Front) -> None:
    outcome = run_outcome(front, "wait P 0 changes within 5")
    assert outcome.ok and outcome.waited is not None and outcome.waited.met


@pytest.mark.slow  # over half a second
def test_watched_rows_are_polled_during_a_wait(front: Front) -> None:
    front.run("watch I 0")
    front.until(lambda: "I0" in front.rows and front.rows["I0"].status == "OK", "I0's value")
    start = len(front.frames)
    # Polls run while the deadline is more than a timeout (1 s here) away.
    outcome = run_outcome(front, "wait I 1 >= 100 within 1.5")
    assert outcome.waited is not None and not outcome.waited.met
    during = [f for f in front.frames[start:] if f.direction == "tx"]
    first_read = next(n for n, f in enumerate(during) if f.data == b"GET:RC8:1:I:\r")
    last_read = max(n for n, f in enumerate(during) if f.data == b"GET:RC8:1:I:\r")
    polls = [f for f in during[first_read:last_read] if f.poll and f.data == b"GET:RC8:0:I:\r"]
    assert len(polls) >= 3  # interval 0.05 s over the first half second


def test_cancel_ends_a_long_wait(front: Front) -> None:
    seq = front.engine.submit("wait I 1 >= 100 within 60")
    front.until(lambda: b"GET:RC8:1:I:\r" in front.sent(), "the wait's first read")
    threading.Timer(0.1, front.engine.cancel).start()
    front.until(lambda: seq in front.results, "the cancelled wait's end")  # long before 60 s
    (outcome,) = front.results[seq].feedback
    assert isinstance(outcome, Outcome) and not outcome.ok
    assert outcome.error is not None and outcome.error.startswith("wait cancelled")


# ------------------------------------------------------------------ run


def run_script(
    script: str, *options: str, keep_going: bool = False
) -> subprocess.CompletedProcess[str]:
    going = ["--keep-going"] if keep_going else []
    return subprocess.run(
        [sys.executable, "-m", "rac_console", *options, "run", *going, "-"],
        input=script,
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.mark.slow
def test_a_cell_check_script_passes() -> None:
    result = run_script("put IO 20 on\nwait IO 20 on within 2\nget P 0\n", "--json")
    assert result.returncode == 0, result.stderr
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert [line["line"] for line in lines] == [1, 2, 3]
    assert lines[1]["wait"]["met"] is True and lines[1]["value"] is True


@pytest.mark.slow
def test_a_wait_that_times_out_fails_the_script_with_exit_1() -> None:
    result = run_script("wait I 1 >= 100 within 0.2\nget I 1\n", keep_going=True)
    assert result.returncode == 1
    assert "line 1: I1 >= 100: not met within 0.2 s" in result.stderr
    assert "Traceback" not in result.stderr
    assert "I1 = 1" in result.stdout  # the script went on (--keep-going)
    stopped = run_script("wait I 1 >= 100 within 0.2\nget I 1\n")
    assert stopped.returncode == 1 and "I1 = 1" not in stopped.stdout  # it stops there


# ------------------------------------------------------------------ REPL


async def test_the_repl_waits_and_logs(tmp_path: Path) -> None:
    from tests.support.drivers import Driver

    csv_path = tmp_path / "repl.csv"
    driver = Driver(tmp_path, interval=0.02)

    async def steps(d: Driver) -> None:
        d.type("wait IO 128 on within 2\r")
        await d.until(lambda out: "✓ IO128 on after" in out, "the wait")
        d.type("wait I 1 > 5 within 0.1\r")
        await d.until(lambda out: "I1 > 5: not met within 0.1 s" in out, "the timeout")
        d.type(f"log {csv_path}\r")
        await d.until(lambda out: "from the first poll cycle" in out, "the log's start")
        d.type("log stop\r")
        await d.until(lambda out: "stopped before its first row" in out, "the log's end")

    await driver.run(steps)
    assert not csv_path.read_text()  # opened to check it can be written: no row, no header


@pytest.mark.parametrize(
    ("typed", "needs"),
    [
        ("wait IO 128 ", "CONDITION [within SECONDS]"),
        ("wait I 10 >= ", "VALUE [within SECONDS]"),
        ("wait I 10 >= 100 ", "[within SECONDS]"),
        ("wait P 0 changes within ", "SECONDS"),
        ("wait P 0 changes within 5 ", ""),
    ],
)
def test_the_hint_says_what_a_wait_still_needs(typed: str, needs: str) -> None:
    from rac_console.present.completion import hint

    assert hint(typed) == needs


def test_a_wait_on_a_bit_completes_its_conditions() -> None:
    from rac_console.present.completion import complete

    assert [c.text for c in complete("wait IO 128 ")] == ["on", "off", "changes", "==", "!="]
    assert [c.text for c in complete("wait I 1 ")] == [
        "changes", "==", "!=", "<", "<=", ">", ">="
    ]  # fmt: skip
    assert [c.text for c in complete("wait P 0 ")] == ["changes", "==", "!="]


def test_a_value_that_could_not_be_written_cannot_be_waited_for() -> None:
    with pytest.raises(InputError, match="control character"):
        parse_wait("S 0 == \x1b[31mRED\x07")


def test_a_condition_reaches_the_terminal_escaped() -> None:
    from rac_console.commands.outcome import Waited
    from rac_console.present.render import outcome_text

    outcome = Outcome(
        "GET:RC8:0:S:",
        ExitStatus.OK,
        parse_wait("S 0 changes").var,
        "0,8,x",
        None,
        waited=Waited("S0 == \x1b[31mRED\x07", True, 0.1, 3, 1.0),
    )
    shown = outcome_text(outcome).plain
    assert "\x1b" not in shown and "\x07" not in shown
    assert "\\x1b[31mRED\\x07" in shown


@pytest.mark.slow  # over half a second
def test_no_poll_that_could_outlast_the_deadline_starts_during_a_wait(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A slow watched row can take up to a timeout per poll: a wait must not start one
    that could end after its deadline (it would end late, saying "not met within ...").

    Checked on the engine's own choice, not on frame stamps against a margin: each poll
    step begun during the wait is noted with the engine's clock reading it was chosen on
    (the last ``perf_counter()`` the engine's thread read) and the wait's deadline."""
    import threading
    import time

    import rac_console.engine.polling.poller as poller_module
    from rac_console.engine.polling.poller import Poller
    from tests.support.servers import RecordingServer

    class Clock:
        """``time`` for the engine module: the real one, noting each thread's last
        ``perf_counter()``."""

        def __init__(self) -> None:
            self.last: dict[int, float] = {}

        def perf_counter(self) -> float:
            now = time.perf_counter()
            self.last[threading.get_ident()] = now
            return now

        def __getattr__(self, name: str) -> object:
            return getattr(time, name)

    def reply(line: bytes) -> bytes | None:
        if line.startswith(b"GET:RC8:5:I:"):
            time.sleep(0.3)  # the controller's slow answer, within the timeout
        return b"0,3,1\r"

    clock = Clock()
    server = RecordingServer(reply)
    timeout, within = 0.4, 2.0
    engine = Engine("127.0.0.1", server.port, interval=0.05, timeout=timeout)
    deadlines: list[float] = []  # the deadline of the wait in progress, while it polls
    steps: list[tuple[float, float]] = []  # (the clock a poll step was chosen on, deadline)
    real_poll_until, real_poll_once = Poller.poll_until, Poller.poll_once

    def poll_until(
        self: Poller, until: float, deadline: float, stopping: Callable[[], bool]
    ) -> None:
        deadlines.append(deadline)
        try:
            real_poll_until(self, until, deadline, stopping)
        finally:
            deadlines.pop()

    def poll_once(self: Poller, more: Callable[[], bool] | None = None) -> None:
        if deadlines:
            steps.append((clock.last[threading.get_ident()], deadlines[-1]))
        real_poll_once(self, more)

    monkeypatch.setattr(Poller, "poll_until", poll_until)
    monkeypatch.setattr(Poller, "poll_once", poll_once)
    monkeypatch.setattr(poller_module, "time", clock)
    engine.start()
    front = Front(engine)
    try:
        front.run("watch I 5")
        front.until(lambda: b"GET:RC8:5:I:\r" in front.sent(), "the silent row's first poll")
        asked = time.perf_counter()
        outcome = run_outcome(front, f"wait I 1 >= 100 within {within}")
        answered = time.perf_counter()
        assert outcome.waited is not None and not outcome.waited.met
        tx = [f for f in front.frames if f.direction == "tx"]
        reads = [f for f in tx if f.data == b"GET:RC8:1:I:\r"]
        assert len(reads) == outcome.waited.reads
        polls = [f for f in tx if f.poll and reads[0].time < f.time < reads[-1].time]
        assert polls, "the watched row is polled during the wait"
        assert steps, "the engine took poll steps during the wait"
        # The deadline the engine kept is the wait's: set while the wait was handled.
        assert all(asked + within <= deadline <= answered + within for _, deadline in steps)
        # No step began that a whole timeout could carry past that deadline.
        assert all(deadline - chosen > timeout for chosen, deadline in steps), [
            round(deadline - chosen, 3) for chosen, deadline in steps
        ]
    finally:
        engine.stop()
        server.close()


def test_an_error_answer_ends_the_wait_at_once(front: Front) -> None:
    outcome = run_outcome(front, "wait I 30000 == 1 within 5")  # no such I in the simulator
    assert outcome.status == ExitStatus.CONTROLLER_ERROR
    assert outcome.waited is not None and outcome.waited.reads == 1
    assert "controller answered" in (outcome.error or "")


def test_an_unreachable_controller_is_said_as_such() -> None:
    import socket

    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    engine = Engine("127.0.0.1", port, timeout=0.5)
    engine.start(connect=False)
    front = Front(engine)
    try:
        outcome = run_outcome(front, "wait I 1 >= 5 within 3")
    finally:
        engine.stop()
    assert outcome.status == ExitStatus.TRANSPORT
    assert outcome.waited is not None and outcome.waited.reads == 1
    assert "not met within" not in (outcome.error or "")


@pytest.mark.parametrize("number", ["1_000", "0x10", "1e400", "+-1"])
def test_a_threshold_is_a_plain_number(number: str) -> None:
    with pytest.raises(InputError, match="needs one number"):
        parse_wait(f"I 1 >= {number}")
