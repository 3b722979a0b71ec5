"""The library (``import rac_console as rac``) as a script uses it, judged from the
controller's side: the built-in simulator and fake controllers that record every line,
over real sockets. Values come back typed; a put is read back (GET, PUT, GET on the
wire); what the rules refuse sends nothing; a PUT that got no answer is one PUT, never
sent again; several threads share one connection."""

from __future__ import annotations

import itertools
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

import rac_console as rac
from tests.support.drivers import profile
from tests.support.servers import Memory, fixed_reply, unused_port

HOST = "127.0.0.1"


def test_every_type_comes_back_as_its_python_type() -> None:
    values: dict[str, rac.Value] = {
        "I": -5,
        "F": 1.5,
        "D": 0.1,
        "S": ' say "hi" ',
        "IO": True,
        "V": (1.0, 2.0, 3.0),
        "P": (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0),
        "J": tuple(float(n) for n in range(8)),
        "T": tuple(float(n) for n in range(10)),
    }
    with rac.connect("sim") as rc:
        for kind, value in values.items():
            written = rc.put(kind, 20, value)
            assert written.verified is True, (kind, written)
            got = rc.get(kind.lower(), 20)  # the type in any case, as the console takes it
            assert got == value and type(got) is type(value), (kind, got)
        assert type(rc.get("I", 20)) is int and type(rc.get("F", 20)) is float
        assert len(rc.get("P", 0)) == 7 and all(type(x) is float for x in rc.get("P", 0))


def test_a_put_is_read_before_and_after_as_the_console_does(recording) -> None:
    server = recording(Memory())
    with rac.connect(f"{HOST}:{server.port}") as rc:
        written = rc.put("I", 10, 5)
    assert written == rac.Written("I10", 5, 10, 5, True)
    assert server.lines == [b"GET:RC8:10:I:", b"PUT:RC8:10:I:3,5", b"GET:RC8:10:I:"]


def test_a_put_without_verify_is_the_put_alone(recording) -> None:
    server = recording(Memory())
    with rac.connect(HOST, port=server.port) as rc:
        written = rc.put("I", 10, 5, verify=False)
    assert (written.before, written.read_back, written.verified) == (None, None, None)
    assert server.lines == [b"PUT:RC8:10:I:3,5"]


@pytest.mark.parametrize(
    ("kind", "value", "says"),
    [
        ("I", True, "I takes an int, got True"),
        ("I", 2**31, "out of range for I (VT_I4"),
        ("I", "5", "I takes an int, got '5'"),
        ("F", float("nan"), "F needs a number such as 1.5"),
        ("D", "1.5", "D takes a float (or an int)"),
        ("P", (1.0, 2.0), "P needs 7 values: X Y Z Rx Ry Rz Fig, got 2"),
        ("V", ("1", 2, 3), "V takes a tuple of 3 floats (X Y Z)"),
        ("S", "a\rb", "S cannot hold CR or LF"),
        ("S", "é", "RAC text is ASCII"),
        ("S", "x" * 300, "RAC allows at most 256"),
        ("IO", 1, "IO takes a bool (True for on, False for off)"),
        ("Q", 1, "unknown variable type 'Q'"),
        ("IO10", True, "unknown variable type 'IO10'"),
    ],
)
def test_a_value_that_cannot_be_sent_is_refused_with_nothing_on_the_wire(
    recording, kind: str, value: object, says: str
) -> None:
    server = recording(Memory())
    with rac.connect(HOST, port=server.port) as rc:
        with pytest.raises(rac.Refused, match=None) as refused:
            rc.put(kind, 10, value)  # type: ignore[arg-type]
        with pytest.raises(rac.Refused, match="index must be a whole number"):
            rc.get("I", -1)
        with pytest.raises(rac.Refused, match="index"):
            rc.get("I", True)
    assert says in str(refused.value)
    assert server.lines == []


def _config(tmp_path: Path, *tables: str) -> Path:
    path = tmp_path / "rules.toml"
    path.write_text("".join(tables), encoding="utf-8")
    return path


def test_read_only_sends_only_well_formed_gets(recording) -> None:
    server = recording(Memory())
    with rac.connect(HOST, port=server.port, read_only=True) as rc:
        assert rc.writes == "read-only"
        with pytest.raises(rac.Refused, match=r"PUT I10 refused: read-only mode is on"):
            rc.put("I", 10, 5)
        with pytest.raises(rac.Refused, match="read-only"):
            rc.send("PUT:RC8:10:I:3,5")
        with pytest.raises(rac.Refused, match="read-only"):
            rc.send("HELLO")
        assert rc.send("GET:RC8:10:I:") == rac.Sent(10, 0, "0,3,10")
    assert server.lines == [b"GET:RC8:10:I:"]


def test_a_profile_rules_wherever_its_controller_is_named_the_strictest_of_them(
    recording, tmp_path: Path
) -> None:
    """Two profiles name one controller, one open and one read-only: the script that
    names the open one, or the address (written another way), gets the read-only rules."""
    server = recording(Memory())
    rules = _config(
        tmp_path,
        profile("bench", server.port, 'writes = "open"'),
        profile("Line2", server.port, 'writes = "read-only"'),
    )
    for named in ("bench", "LINE2", f"localhost:{server.port}", f"{HOST}:{server.port}"):
        with rac.connect(named, config=rules) as rc:
            assert rc.writes == "read-only", named
            with pytest.raises(rac.Refused, match=r"profile .*read-only"):
                rc.put("I", 10, 5)
    assert server.lines == []


def test_an_allow_list_refuses_what_it_does_not_name(recording, tmp_path: Path) -> None:
    server = recording(Memory())
    rules = _config(tmp_path, profile("cell3", server.port, 'allow = ["I 100-199"]'))
    with rac.connect(f"{HOST}:{server.port}", config=rules) as rc:
        with pytest.raises(rac.Refused, match=r"allows writes only to I 100-199"):
            rc.put("I", 10, 5)
        with pytest.raises(rac.Refused, match=r"allows writes only to I 100-199"):
            rc.send("PUT:RC8:10:I:3,5")
        assert server.lines == []
        assert rc.put("I", 100, 7).verified is True
    assert server.lines == [b"GET:RC8:100:I:", b"PUT:RC8:100:I:3,7", b"GET:RC8:100:I:"]


def test_a_confirm_profile_asks_the_script_or_refuses(recording, tmp_path: Path) -> None:
    server = recording(Memory())
    rules = _config(tmp_path, profile("cell3", server.port, 'writes = "confirm"'))
    with (
        rac.connect("cell3", config=rules) as rc,
        pytest.raises(rac.Refused, match=r'asks before every write \(writes = "confirm"\)'),
    ):
        rc.put("I", 10, 5)
    assert server.lines == []  # no answer given: nothing, not even the read before

    asked: list[tuple[str, rac.Value | None, rac.Value]] = []

    def no(variable: str, now: rac.Value | None, value: rac.Value) -> bool:
        asked.append((variable, now, value))
        return False

    with (
        rac.connect("cell3", config=rules, confirm=no) as rc,
        pytest.raises(rac.Refused, match="PUT I10 not confirmed: nothing was sent"),
    ):
        rc.put("I", 10, 5)
    assert asked == [("I10", 10, 5)]
    assert b"PUT:RC8:10:I:3,5" not in server.lines

    server.lines.clear()
    with rac.connect("cell3", config=rules, confirm=lambda *question: True) as rc:
        assert rc.put("I", 10, 5).verified is True
    with rac.connect("cell3", config=rules, yes=True) as rc:
        assert rc.put("I", 10, 6).before == 5
    assert server.lines.count(b"PUT:RC8:10:I:3,5") == 1
    assert server.lines[-3:] == [b"GET:RC8:10:I:", b"PUT:RC8:10:I:3,6", b"GET:RC8:10:I:"]


def test_a_put_that_gets_no_answer_is_sent_once_and_said_unknown(recording) -> None:
    server = recording(Memory(puts="swallow"))
    with rac.connect(HOST, port=server.port, timeout=2) as rc:
        with pytest.raises(rac.OutcomeUnknown, match="outcome unknown") as unknown:
            rc.put("I", 10, 5)
        assert rc.get("I", 11) == 11  # the connection goes on
    assert [line for line in server.lines if line.startswith(b"PUT")] == [b"PUT:RC8:10:I:3,5"]
    written = unknown.value.written
    assert written is not None and written.before == 10 and written.verified is None
    assert server.lines[:2] == [b"GET:RC8:10:I:", b"PUT:RC8:10:I:3,5"]


def test_a_raw_put_that_gets_no_answer_is_unknown_too(recording) -> None:
    server = recording(Memory(puts="swallow"))
    with rac.connect(HOST, port=server.port, timeout=2) as rc, pytest.raises(rac.OutcomeUnknown):
        rc.send("PUT:RC8:10:I:3,5")
    assert [line for line in server.lines if line.startswith(b"PUT")] == [b"PUT:RC8:10:I:3,5"]


def test_a_controller_that_answers_s_ok_and_keeps_its_value_is_caught(recording) -> None:
    server = recording(Memory(puts="ignore"))
    with (
        rac.connect(HOST, port=server.port) as rc,
        pytest.raises(rac.ReadBackMismatch, match="holds another value") as caught,
    ):
        rc.put("I", 10, 5)
    assert caught.value.written == rac.Written("I10", 5, 10, 10, False)


def test_an_error_answer_is_a_controller_error_with_its_code(recording) -> None:
    server = recording(fixed_reply(b"-2147024809\r"))
    with rac.connect(HOST, port=server.port) as rc:
        with pytest.raises(rac.ControllerError) as error:
            rc.get("I", 10)
        with pytest.raises(rac.ControllerError) as raw:
            rc.send("GET:RC8:10:I:")
    assert (error.value.code, error.value.name) == (0x80070057, "E_INVALIDARG")
    assert "E_INVALIDARG" in str(error.value) and raw.value.name == "E_INVALIDARG"


def test_a_get_without_an_answer_is_a_timeout(recording) -> None:
    server = recording(fixed_reply(None))
    with (
        rac.connect(HOST, port=server.port, timeout=0.5) as rc,
        pytest.raises(TimeoutError, match=r"no reply within 0.5 s") as timed_out,
    ):
        rc.get("I", 10)
    assert isinstance(timed_out.value, rac.Timeout) and isinstance(timed_out.value, rac.RacError)


def test_a_controller_that_cannot_be_reached_says_what_check_says() -> None:
    port = unused_port()
    with pytest.raises(rac.ConnectionFailed) as failed:
        rac.connect(HOST, port=port)
    assert isinstance(failed.value, ConnectionError)
    assert failed.value.problem == "refused"
    assert f"cannot connect to {HOST}:{port}" in str(failed.value)
    assert failed.value.hint is not None and "nothing accepts connections" in failed.value.hint


@pytest.mark.parametrize(
    ("call", "says"),
    [
        (lambda: rac.connect(""), "connect to a host"),
        (lambda: rac.connect("a:1", port=2), "name two ports"),
        (lambda: rac.connect("sim", port=0), "from 1 to 65535"),
        (lambda: rac.connect("sim", timeout=0), "timeout is a number of seconds"),
    ],
)
def test_a_target_that_cannot_be_one_is_refused(call: Callable[[], object], says: str) -> None:
    with pytest.raises(rac.Refused, match=says):
        call()


def test_a_broken_config_file_is_refused_naming_it(tmp_path: Path) -> None:
    broken = _config(tmp_path, "[target.cell3]\nhost = 5\n")
    with pytest.raises(rac.Refused, match=r"rules\.toml"):
        rac.connect("cell3", config=broken)


def test_a_config_file_named_but_not_there_is_refused_with_nothing_sent(
    recording, tmp_path: Path
) -> None:
    """A typo in ``config=`` must not read as "no profiles": the read-only profile of the
    endpoint would be lost and a put would write. ``~`` is the user's home, as in a shell."""
    server = recording(Memory())
    missing = tmp_path / "rules.tmol"
    address = f"{HOST}:{server.port}"
    with pytest.raises(rac.Refused, match=r"rules\.tmol \(named by config\) does not exist"):
        rac.connect(address, config=missing)
    with pytest.raises(rac.Refused, match=r"rules\.tmol \(named by config\) does not exist"):
        rac.cell([address], config=str(missing))
    with pytest.raises(rac.Refused, match="config is the path of a config file, not 5"):
        rac.connect(address, config=5)  # type: ignore[arg-type]
    home = Path.home()  # the test's own (the env fixture)
    (home / "rules.toml").write_text(
        profile("cell3", server.port, 'writes = "read-only"'), encoding="utf-8"
    )
    with rac.connect(address, config="~/rules.toml") as rc:
        assert rc.writes == "read-only" and rc.profile == "cell3"
        with pytest.raises(rac.Refused, match="profile cell3 is read-only"):
            rc.put("I", 10, 5)
    assert len(server.connections()) == 1 and server.lines == []  # the one through ~


def test_a_closed_connection_sends_nothing(recording) -> None:
    server = recording(Memory())
    rc = rac.connect(HOST, port=server.port)
    rc.close()
    with pytest.raises(rac.Refused, match="closed"):
        rc.get("I", 1)
    assert server.lines == []


def test_threads_share_one_connection_each_getting_its_own_answer(recording) -> None:
    server = recording(Memory())
    answers: dict[int, list[int]] = {}

    def reader(first: int, rc: rac.Connection) -> None:
        answers[first] = [rc.get("I", first + n) for n in range(0, 200, 8)]

    with rac.connect(HOST, port=server.port) as rc:
        threads = [threading.Thread(target=reader, args=(n, rc)) for n in range(8)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(60)
    assert {first: values for first, values in answers.items()} == {
        first: list(range(first, first + 200, 8)) for first in range(8)
    }
    assert len(server.lines) == 8 * 25 and server.accepted == 1


def test_a_watch_reads_each_variable_each_cycle_and_goes_on_after_a_failure(recording) -> None:
    def answers(line: bytes) -> bytes:
        return b"-2147024809\r" if line == b"GET:RC8:1:I:" else Memory()(line)  # type: ignore[return-value]

    server = recording(answers)
    with rac.connect(HOST, port=server.port) as rc:
        readings = list(itertools.islice(rc.watch("I 0-1", "I[5]", every=0.01), 6))
    assert [r.name for r in readings] == ["I0", "I1", "I5"] * 2
    first, failed, _ = readings[:3]
    assert first.ok and first.value == 0 and failed.value is None
    assert failed.error is not None and "E_INVALIDARG" in failed.error and not failed.ok
    assert readings[3].ok and readings[3].time >= first.time


def test_a_watch_refuses_what_the_console_would(recording) -> None:
    server = recording(Memory())
    with rac.connect(HOST, port=server.port) as rc:
        with pytest.raises(rac.Refused, match="watch takes variables only"):
            rc.watch("I 1 pick")
        with pytest.raises(rac.Refused, match="every must be from 0"):
            rc.watch("I 1", every=-1)
        with pytest.raises(rac.Refused, match="watch needs a variable"):
            rc.watch()
    assert server.lines == []


def test_an_s_ok_whose_read_back_gets_no_answer_is_not_taken_for_a_write(recording) -> None:
    memory = Memory()
    gets = 0

    def answers(line: bytes) -> bytes | None:
        nonlocal gets
        gets += line.startswith(b"GET")
        return None if gets == 2 else memory(line)  # type: ignore[return-value]

    server = recording(answers)
    with (
        rac.connect(HOST, port=server.port, timeout=0.5) as rc,
        pytest.raises(rac.ReadBackMismatch, match="read back failed: no reply") as caught,
    ):
        rc.put("I", 10, 5)
    assert caught.value.written == rac.Written("I10", 5, 10, None, None)
    assert server.lines == [b"GET:RC8:10:I:", b"PUT:RC8:10:I:3,5", b"GET:RC8:10:I:"]


def test_an_exception_in_the_script_s_confirm_comes_back_unchanged_and_no_put_goes_out(
    recording, tmp_path: Path
) -> None:
    server = recording(Memory())
    rules = _config(tmp_path, profile("cell3", server.port, 'writes = "confirm"'))

    class Mine(Exception):
        pass

    def ask(variable: str, now: rac.Value | None, value: rac.Value) -> bool:
        raise Mine(variable)

    with rac.connect("cell3", config=rules, confirm=ask) as rc:
        with pytest.raises(Mine, match="I10"):
            rc.put("I", 10, 5)
        assert rc.get("I", 10) == 10  # the connection goes on
    assert server.lines == [b"GET:RC8:10:I:", b"GET:RC8:10:I:"]


def test_a_reply_that_cannot_be_read_is_said_so_not_a_lost_connection(recording) -> None:
    server = recording(fixed_reply(b"garbage\x1b[31m\r"))
    with rac.connect(HOST, port=server.port) as rc, pytest.raises(rac.RacError) as caught:
        rc.get("I", 10)
    unreadable = caught.value
    assert isinstance(unreadable, rac.UnreadableReply)
    assert not isinstance(unreadable, rac.ConnectionFailed | ConnectionError)
    said = str(unreadable)
    assert said.startswith("the controller's reply could not be read: bad reply 'garbage\\x1b[31m'")
    assert "\x1b" not in said and said.endswith("(request GET:RC8:10:I:)")
    assert unreadable.raw == b"garbage\x1b[31m"
    assert server.lines == [b"GET:RC8:10:I:"]


@pytest.mark.parametrize(
    ("reply", "name", "says"),
    [
        (b"1\r", None, "controller answered 0x00000001: not S_OK, the one success RAC defines"),
        (b"-2147000000\r", None, "controller answered 0x80076140: unknown error"),
        (b"-2147024809\r", "E_INVALIDARG", "E_INVALIDARG 0x80070057: invalid argument"),
    ],
)
def test_any_answer_but_s_ok_is_a_controller_error_said_as_what_it_is(
    recording, reply: bytes, name: str | None, says: str
) -> None:
    server = recording(fixed_reply(reply))
    with rac.connect(HOST, port=server.port) as rc, pytest.raises(rac.ControllerError) as error:
        rc.get("I", 10)
    assert error.value.name == name and says in str(error.value)
    assert ": success" not in str(error.value)


def test_a_read_before_a_put_that_times_out_is_named_as_the_request_that_did(
    recording,
) -> None:
    server = recording(fixed_reply(None))
    with (
        rac.connect(HOST, port=server.port, timeout=0.5) as rc,
        pytest.raises(rac.Timeout) as timed_out,
    ):
        rc.put("I", 10, 5)
    said = str(timed_out.value)
    assert said.startswith("PUT I10 not sent: reading its value first failed: no reply")
    assert said.endswith("(request GET:RC8:10:I:)") and "request PUT" not in said
    assert server.lines == [b"GET:RC8:10:I:"]


def test_a_port_for_the_built_in_simulator_is_refused_not_ignored() -> None:
    with pytest.raises(rac.Refused, match="port=5007 does not apply to 'sim'"):
        rac.connect("sim", port=5007)
