"""Read-back after every PUT, and a target's write rules (allow, confirm), before the wire.

The engine's tests run on the built-in simulator; the CLI's are the real program as a
subprocess, against the simulator or a server written here that ignores a PUT.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rac_console.commands.language import Put, VarRef
from rac_console.commands.outcome import ExitStatus, Outcome
from rac_console.commands.policy import AllowRange, WritePolicy, Writes, parse_allow
from rac_console.commands.readback import same_value
from rac_console.engine import ConfirmWrite, Engine
from rac_console.present.render import outcome_text
from rac_console.protocol import Variant, kind_of
from rac_console.protocol.vartypes import VT
from tests.support.drivers import Front, cli, one_error_line
from tests.support.servers import RecordingServer


def ignoring_put(held: bytes = b"0,3,14\r") -> Callable[[bytes], bytes]:
    """A controller that answers S_OK to every PUT and keeps its old value."""

    def reply(line: bytes) -> bytes:
        return b"0\r" if line.startswith(b"PUT:") else held

    return reply


def silent_put(held: bytes = b"0,3,15\r") -> Callable[[bytes], bytes | None]:
    """A controller that takes the PUT but never answers it (its value did change)."""

    def reply(line: bytes) -> bytes | None:
        return None if line.startswith(b"PUT:") else held

    return reply


@pytest.fixture
def server() -> Iterator[Callable[..., RecordingServer]]:
    made: list[RecordingServer] = []

    def make(reply: Callable[[bytes], bytes | None]) -> RecordingServer:
        made.append(RecordingServer(reply))
        return made[-1]

    yield make
    for each in made:
        each.close()


def engine_front(**options: object) -> Iterator[Front]:
    engine = Engine(None, interval=0.05, timeout=1.0, **options)  # type: ignore[arg-type]
    engine.start()
    try:
        yield Front(engine)
    finally:
        engine.stop()


def outcome_of(front: Front, line: str) -> Outcome:
    seq = front.engine.submit(line)
    front.until(lambda: seq in front.results, f"the answer to {line!r}")
    (feedback,) = front.results[seq].feedback
    assert isinstance(feedback, Outcome), feedback
    return feedback


def sent(front: Front) -> list[str]:
    return [f.data.decode().rstrip("\r") for f in front.frames if f.direction == "tx"]


# ------------------------------------------------------------- comparing values


def test_a_single_float_read_back_as_the_controller_rounds_it_matches() -> None:
    written = Put.of(VarRef(kind_of("F"), 1), Variant(VT.R4, 1.1), "4,1.1").value
    assert same_value(kind_of("F"), written, Variant(VT.R4, 1.100000023841858))
    assert not same_value(kind_of("F"), written, Variant(VT.R4, 1.2))


def test_an_io_bit_read_back_as_minus_one_is_on() -> None:
    assert same_value(kind_of("IO"), Variant(VT.BOOL, True), Variant(VT.I4, -1))
    assert not same_value(kind_of("IO"), Variant(VT.BOOL, True), Variant(VT.BOOL, False))


def test_a_position_differs_in_one_field() -> None:
    kind = kind_of("P")
    written = Variant(8196, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, -1.0])
    assert same_value(kind, written, Variant(8196, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, -1.0]))
    assert not same_value(kind, written, Variant(8196, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 1.0]))


# ------------------------------------------------------------------ the engine


@pytest.fixture
def plain() -> Iterator[Front]:
    yield from engine_front()


def test_a_put_shows_the_value_before_and_the_value_read_back(plain: Front) -> None:
    plain.run("put I 10 14")
    outcome = outcome_of(plain, "put I 10 15")
    assert outcome.ok
    assert outcome.before == Variant(VT.I4, 14)
    assert outcome.read_back == Variant(VT.I4, 15)
    assert outcome.verified is True
    assert outcome_text(outcome).plain.startswith("I10: 14 → 15  S_OK  read back 15 ✓")
    assert sent(plain)[-3:] == ["GET:RC8:10:I:", "PUT:RC8:10:I:3,15", "GET:RC8:10:I:"]


def test_a_watched_variable_is_not_read_before_the_put(plain: Front) -> None:
    plain.run("put I 11 7")
    plain.run("watch I 11")
    plain.until(lambda: plain.rows.get("I11") is not None and "7" in str(plain.rows["I11"]), "I11")
    count = len(plain.frames)
    outcome = outcome_of(plain, "put I 11 8")
    assert outcome.before == Variant(VT.I4, 7)
    typed = [
        f.data.decode().rstrip("\r")
        for f in plain.frames[count:]
        if f.direction == "tx" and not f.poll
    ]
    assert typed == ["PUT:RC8:11:I:3,8", "GET:RC8:11:I:"]
    assert outcome.verified is True


def test_no_verify_sends_the_put_alone() -> None:
    for front in engine_front(verify=False):
        outcome = outcome_of(front, "put I 10 15")
        assert outcome.ok and outcome.before is None and outcome.read_back is None
        assert sent(front) == ["PUT:RC8:10:I:3,15"]
        assert outcome_text(outcome).plain.startswith("I10 ← 15  S_OK")


def test_allow_refuses_a_write_outside_its_ranges_before_the_wire() -> None:
    policy = WritePolicy(allow=(parse_allow("I 50-99"),), source="profile cell3")
    for front in engine_front(policy=policy):
        outcome = outcome_of(front, "put I 10 15")
        assert outcome.status == ExitStatus.REFUSED
        assert "profile cell3 allows writes only to I 50-99" in (outcome.error or "")
        raw = outcome_of(front, "PUT:RC8:10:I:3,15")
        assert raw.status == ExitStatus.REFUSED
        assert sent(front) == []
        assert outcome_of(front, "put I 60 1").ok
        assert "PUT:RC8:60:I:3,1" in sent(front)


def test_an_allow_range_reads_as_written() -> None:
    assert str(parse_allow("IO 64-71")) == "IO 64-71"
    assert parse_allow("P[3]") == AllowRange(kind_of("P"), 3, 3)


class AnsweringFront(Front):
    """A front end that answers every confirm question ``answer`` (None: Esc)."""

    def __init__(self, engine: Engine, answer: bool | None) -> None:
        super().__init__(engine)
        self.answer = answer
        self.asked: list[ConfirmWrite] = []

    def take_confirm(self, target: str | None, question: ConfirmWrite) -> None:
        self.asked.append(question)
        if self.answer is None:
            self.engine.cancel(queued=True)
        else:
            self.engine.answer_confirm(question.seq, self.answer)


@pytest.mark.parametrize("answer", [False, None], ids=["no", "esc"])
def test_a_confirm_target_writes_nothing_unless_the_answer_is_yes(answer: bool | None) -> None:
    engine = Engine(None, timeout=1.0, policy=WritePolicy(Writes.CONFIRM, source="profile cell3"))
    engine.start()
    try:
        front = AnsweringFront(engine, True)
        assert outcome_of(front, "put I 10 14").ok
        front.answer = answer
        outcome = outcome_of(front, "put I 10 15")
        assert outcome.status == ExitStatus.REFUSED
        assert "nothing was sent" in (outcome.error or "")
        question = front.asked[-1]
        assert (question.var, question.before, question.after) == ("I10", "14", "15")
        assert "PUT:RC8:10:I:3,15" not in sent(front)
        assert outcome_of(AnsweringFront(engine, True), "get I 10").variant == Variant(VT.I4, 14)
    finally:
        engine.stop()


@pytest.mark.slow
def test_cli_put_reads_back_and_says_so(env: dict[str, str]) -> None:
    result = cli(env, "run", "-", stdin="put I 10 14\nput I 10 15\n")
    assert result.returncode == 0, result.stderr
    assert "I10: 14 → 15  S_OK  read back 15 ✓" in result.stdout


@pytest.mark.slow
def test_cli_put_ignored_by_the_controller_exits_1_with_a_cross(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
) -> None:
    controller = server(ignoring_put())
    result = cli(env, *controller.args, "put", "I", "10", "15")
    assert result.returncode == 1
    assert "I10: 14 → 15  S_OK  read back 14 ✗" in one_error_line(result)
    assert controller.lines == [b"GET:RC8:10:I:", b"PUT:RC8:10:I:3,15", b"GET:RC8:10:I:"]
    data = json.loads(cli(env, *controller.args, "put", "I", "10", "15", "--json").stdout)
    assert data["before"] == 14 and data["read_back"] == 14 and data["verified"] is False


@pytest.mark.slow
def test_cli_no_verify_sends_only_the_put(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
    tmp_path: Path,
) -> None:
    controller = server(ignoring_put())
    record = tmp_path / "frames.jsonl"
    result = cli(env, *controller.args, "put", "I", "10", "15", "--no-verify")
    assert result.returncode == 0, result.stderr
    assert controller.lines == [b"PUT:RC8:10:I:3,15"]
    cli(env, *controller.args, "--record", str(record), "put", "I", "10", "15")
    frames = [json.loads(line) for line in record.read_text().splitlines()]
    assert [f["dir"] for f in frames] == ["tx", "rx"] * 3


@pytest.mark.slow
def test_a_timed_out_put_is_unknown_and_the_read_back_says_what_is_held(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
) -> None:
    controller = server(silent_put())
    result = cli(env, *controller.args, "--timeout", "0.5", "put", "I", "10", "15", "--json")
    assert result.returncode == 3
    data = json.loads(result.stdout)
    assert "outcome unknown" in data["error"]
    assert data["read_back"] == 15
    assert "read back 15" in result.stderr


def failing_read_back(held: bytes = b"0,3,14\r") -> Callable[[bytes], bytes]:
    """A controller that takes the PUT (S_OK), then answers every later GET E_FAIL."""
    gets = 0

    def reply(line: bytes) -> bytes:
        nonlocal gets
        if line.startswith(b"PUT:"):
            return b"0\r"
        gets += 1
        return held if gets == 1 else b"-2147467259\r"  # E_FAIL, signed decimal

    return reply


@pytest.mark.slow
def test_a_read_back_that_fails_is_said_once(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
) -> None:
    controller = server(failing_read_back())
    result = cli(env, *controller.args, "put", "I", "10", "15")
    assert result.returncode == 1, result.stderr
    line = one_error_line(result)
    assert "I10: 14 → 15  S_OK  read back failed: " in line
    assert "E_FAIL" in line
    assert (result.stdout + result.stderr).count("read back failed") == 1, line
    assert controller.lines == [b"GET:RC8:10:I:", b"PUT:RC8:10:I:3,15", b"GET:RC8:10:I:"]

    controller = server(failing_read_back())
    result = cli(env, *controller.args, "put", "I", "10", "15", "--json")
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr
    (data,) = [json.loads(line) for line in result.stdout.splitlines() if line.strip()]
    assert data["ok"] is False
    assert (data["result_name"], data["response"]) == ("S_OK", "0")  # the PUT's answer
    assert (data["before"], data["read_back"], data["verified"]) == (14, None, None)
    assert data["read_back_error"].startswith("read back failed: ")
    assert "E_FAIL" in data["read_back_error"]


def profile_env(base: dict[str, str], tmp_path: Path, port: int, rules: str) -> dict[str, str]:
    config = tmp_path / "config.toml"
    config.write_text(
        f'[target.cell3]\nhost = "127.0.0.1"\nport = {port}\nlabel = "Cell 3"\n{rules}\n',
        encoding="utf-8",
    )
    return base | {"RAC_CONSOLE_CONFIG": str(config)}


@pytest.mark.slow
def test_cli_allow_refuses_outside_its_ranges_with_the_rule_and_nothing_sent(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
    tmp_path: Path,
) -> None:
    controller = server(ignoring_put(b"0,3,5\r"))
    cell = profile_env(env, tmp_path, controller.port, 'allow = ["I 100-199", "IO 64-71"]')
    result = cli(cell, "-H", "cell3", "put", "I", "10", "5")
    assert result.returncode == 2
    assert "profile cell3 allows writes only to I 100-199, IO 64-71" in one_error_line(result)
    refused = cli(cell, "-H", "cell3", "send", "PUT:RC8:10:I:3,5")
    assert refused.returncode == 2
    hidden = cli(cell, "-H", "cell3", "send", "\x0bPUT:RC8:10:I:3,5")  # a lenient controller
    assert hidden.returncode == 2
    assert controller.lines == []
    allowed = cli(cell, "-H", "cell3", "put", "I", "150", "5")
    assert allowed.returncode == 0, allowed.stderr
    assert b"PUT:RC8:150:I:3,5" in controller.lines


@pytest.mark.slow
def test_cli_writes_to_a_confirm_target_only_with_yes(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
    tmp_path: Path,
) -> None:
    controller = server(ignoring_put(b"0,3,5\r"))
    cell = profile_env(env, tmp_path, controller.port, 'writes = "confirm"')
    refused = cli(cell, "-H", "cell3", "put", "I", "10", "5")
    assert refused.returncode == 2
    assert "add --yes" in one_error_line(refused)
    script = cli(cell, "-H", "cell3", "run", "-", stdin="get I 10\nput I 10 5\n")
    assert script.returncode == 2
    assert not [line for line in controller.lines if line.startswith(b"PUT:")]
    written = cli(cell, "-H", "cell3", "--json", "put", "I", "10", "5", "--yes")
    assert written.returncode == 0, written.stderr
    data = json.loads(written.stdout)
    assert (data["before"], data["read_back"], data["verified"]) == (5, 5, True)
    assert b"PUT:RC8:10:I:3,5" in controller.lines


class ChangingFront(AnsweringFront):
    """Answers yes, but only after another client wrote ``value`` to the variable asked
    about: the value the question showed is no longer the value before the write."""

    def __init__(self, engine: Engine, value: int) -> None:
        super().__init__(engine, True)
        self.value = value
        self.step = 0  # added to the value after each question

    def take_confirm(self, target: str | None, question: ConfirmWrite) -> None:
        from rac_console.session import Session

        self.asked.append(question)
        status = self.status
        assert status is not None and status.host is not None
        other = Session(status.host, status.port, timeout=2)
        try:
            text = f"3,{self.value}"
            put = Put.of(VarRef(kind_of("I"), 10), Variant(VT.I4, self.value), text)
            other.exchange(put.request)
            self.value += self.step
        finally:
            other.close()
        self.engine.answer_confirm(question.seq, True)


def test_a_value_that_changed_while_the_question_was_open_is_asked_about_again() -> None:
    engine = Engine(None, timeout=1.0, policy=WritePolicy(Writes.CONFIRM, source="profile cell3"))
    engine.start()
    try:
        front = AnsweringFront(engine, True)
        assert outcome_of(front, "put I 10 5").ok
        changing = ChangingFront(engine, 33)  # another tool writes 33 during each question
        outcome = outcome_of(changing, "put I 10 6")
        first, second = changing.asked
        assert (first.before, second.before, second.after) == ("5", "33", "6")
        assert outcome.ok and outcome.before == Variant(VT.I4, 33)  # the value truly before
        assert outcome_text(outcome).plain.startswith("I10: 33 → 6  S_OK  read back 6 ✓")
    finally:
        engine.stop()


def test_a_value_that_keeps_changing_while_asked_is_not_written() -> None:
    engine = Engine(None, timeout=1.0, policy=WritePolicy(Writes.CONFIRM, source="profile cell3"))
    engine.start()
    try:
        front = AnsweringFront(engine, True)
        assert outcome_of(front, "put I 10 5").ok
        changing = ChangingFront(engine, 33)
        changing.step = 1  # a counter the robot program bumps during every question
        outcome = outcome_of(changing, "put I 10 6")
        assert outcome.status == ExitStatus.REFUSED
        assert "while the question was open, 3 times" in (outcome.error or "")
        assert len(changing.asked) == 3
        assert "PUT:RC8:10:I:3,6" not in sent(changing)
    finally:
        engine.stop()


def test_a_raw_put_is_asked_about_by_its_value_and_an_unreadable_one_is_refused() -> None:
    engine = Engine(None, timeout=1.0, policy=WritePolicy(Writes.CONFIRM, source="profile cell3"))
    engine.start()
    try:
        front = AnsweringFront(engine, False)
        outcome_of(front, "PUT:RC8:10:I:3,7")
        assert front.asked[-1].after == "7"
        asked = len(front.asked)
        odd = outcome_of(front, "PUT:RC8:10:I:3,1:60")
        assert odd.status == ExitStatus.REFUSED
        assert "put I 10" in (odd.error or "")  # how to write it instead
        assert len(front.asked) == asked  # refused, not asked about
        assert not [t for t in sent(front) if t.startswith("PUT")]
    finally:
        engine.stop()


@pytest.mark.slow
def test_yes_with_no_verify_sends_the_put_alone_to_a_confirm_target(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
    tmp_path: Path,
) -> None:
    controller = server(ignoring_put(b"0,3,5\r"))
    cell = profile_env(env, tmp_path, controller.port, 'writes = "confirm"')
    result = cli(cell, "-H", "cell3", "put", "I", "10", "5", "--yes", "--no-verify")
    assert result.returncode == 0, result.stderr
    assert controller.lines == [b"PUT:RC8:10:I:3,5"]


@pytest.mark.slow
def test_a_config_file_named_but_missing_is_refused(env: dict[str, str], tmp_path: Path) -> None:
    missing = tmp_path / "nonexist.toml"
    result = cli(env | {"RAC_CONSOLE_CONFIG": str(missing)}, "-H", "cell3", "get", "I", "10")
    assert result.returncode == 2
    line = one_error_line(result)
    assert "nonexist.toml" in line and "RAC_CONSOLE_CONFIG" in line


def test_a_read_only_profile_is_named_in_the_refusal() -> None:
    for front in engine_front(policy=WritePolicy(Writes.READ_ONLY, source="profile cell4")):
        outcome = outcome_of(front, "put I 10 5")
        assert outcome.status == ExitStatus.REFUSED
        assert "profile cell4 is read-only" in (outcome.error or "")
        assert sent(front) == []


@pytest.mark.parametrize(
    "line", ["\x0bPUT:RC8:10:I:3,5", "SIM:SET:delay_ms=1", "put:rc8:10:I:3,5x"]
)
def test_a_raw_line_that_is_no_checkable_put_is_refused_on_an_allow_target(line: str) -> None:
    policy = WritePolicy(allow=(parse_allow("I 50-99"),), source="profile cell3")
    for front in engine_front(policy=policy):
        outcome = outcome_of(front, f"send {line}")
        assert outcome.status == ExitStatus.REFUSED, outcome
        assert sent(front) == []


def test_a_raw_line_that_is_no_checkable_put_is_refused_on_a_confirm_target() -> None:
    for front in engine_front(policy=WritePolicy(Writes.CONFIRM, source="profile cell3")):
        outcome = outcome_of(front, "send SIM:SET:delay_ms=1")  # no PUT it can ask about
        assert outcome.status == ExitStatus.REFUSED
        assert sent(front) == []


@pytest.mark.slow
def test_a_raw_put_written_as_another_type_is_not_called_a_mismatch(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
) -> None:
    controller = server(ignoring_put(b"0,3,15\r"))  # it converted the string "15"
    result = cli(env, *controller.args, "--json", "send", "PUT:RC8:10:I:8,15")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["read_back"] == 15 and data["verified"] is None


@pytest.mark.slow
@pytest.mark.parametrize(
    "text",
    [
        '[target.cell3]\nhost = "h"\nport = ' + "9" * 5000 + "\n",
        '[target.cell3]\nhost = "h"\nallow = ["I 0-' + "0" * 7000 + '1"]\n',
        '[settings]\ntheme = "x"\nio_grid = ' + "1" * 5000 + "\n",
    ],
    ids=["huge-port", "huge-allow", "huge-setting"],
)
def test_a_hostile_config_is_one_line_not_a_traceback(
    env: dict[str, str],
    tmp_path: Path,
    text: str,
) -> None:
    config = tmp_path / "config.toml"
    config.write_text(text, encoding="utf-8")
    result = cli(env | {"RAC_CONSOLE_CONFIG": str(config)}, "get", "I", "1")
    assert result.returncode == 2
    assert "config.toml" in one_error_line(result)


@pytest.mark.slow
def test_a_config_path_that_cannot_be_expanded_is_one_line(env: dict[str, str]) -> None:
    result = cli(env | {"RAC_CONSOLE_CONFIG": "~nosuchuser4242/c.toml"}, "get", "I", "1")
    assert result.returncode == 2
    assert "nosuchuser4242" in one_error_line(result)


@pytest.mark.slow
def test_a_profile_applies_when_its_address_or_its_name_in_another_case_is_typed(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
    tmp_path: Path,
) -> None:
    controller = server(ignoring_put(b"0,3,5\r"))
    cell = profile_env(env, tmp_path, controller.port, 'writes = "read-only"')
    by_address = cli(cell, *controller.args, "put", "I", "10", "5")
    by_case = cli(cell, "-H", "CELL3", "put", "I", "10", "5")
    assert (by_address.returncode, by_case.returncode) == (2, 2)
    assert "profile cell3 is read-only" in one_error_line(by_address)
    assert controller.lines == []


@pytest.mark.slow
def test_a_config_saved_with_a_bom_is_read(
    env: dict[str, str],
    server: Callable[..., RecordingServer],
    tmp_path: Path,
) -> None:
    """Notepad on Windows has saved UTF-8 with a byte order mark."""
    controller = server(ignoring_put(b"0,3,5\r"))
    cell = profile_env(env, tmp_path, controller.port, 'writes = "read-only"')
    config = Path(cell["RAC_CONSOLE_CONFIG"])
    config.write_bytes(b"\xef\xbb\xbf" + config.read_bytes())
    result = cli(cell, "-H", "cell3", "put", "I", "10", "5")
    assert result.returncode == 2
    assert "profile cell3 is read-only" in one_error_line(result)


def test_settings_saved_into_a_file_with_a_bom_keep_it(tmp_path: Path) -> None:
    from rac_console.engine.setup.settings import SettingsFile

    config = tmp_path / "config.toml"
    original = b'\xef\xbb\xbf# cells\r\n[target.cell3]\r\nhost = "h"\r\n'
    config.write_bytes(original)
    SettingsFile(config).save({"hex_view": True})
    data = config.read_bytes()
    assert data.startswith(original)
    assert b"hex_view = true" in data
