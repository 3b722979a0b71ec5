"""``rac-console check`` (issue 20): each step between here and a controller, its words,
and its exit status; the WinSock table behind the words; and the pointers to it from the
console's, the REPL's and a write's connection failures.

The CLI runs as a subprocess (``cli`` and ``env`` from tests/support) against the built-in
simulator, a closed port, a name that cannot resolve, and recording servers
(``tests/support/servers.py``: one that keeps a single session, one that pushes the first
session out, one that never answers).
Every server binds 127.0.0.1 port 0; every wait has a deadline.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import socket
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rac_console.commands.check import (
    STEPS,
    TITLES,
    CheckReport,
    StepResult,
    check_pointer,
    hint,
    report_json,
    step_line,
)
from rac_console.commands.outcome import ExitStatus
from rac_console.engine import Engine
from rac_console.session.sockets import problem_of as _problem
from rac_console.session.sockets import reason_of as _reason
from tests.support.drivers import Front, cli
from tests.support.servers import RecordingServer, Sessions, fixed_reply, unused_port

GET_I0 = b"GET:RC8:0:I:"
ANSWER = b"0,3,123\r"
E_ACCESSDENIED = b"-2147024891\r"  # 0x80070005, as a signed integer


# ----------------------------------------------------------------- helpers


def report_of(result: subprocess.CompletedProcess[str]) -> dict:
    """The one JSON object of ``check --json``, and nothing else on stdout."""
    assert "Traceback" not in result.stderr, result.stderr
    [line] = result.stdout.splitlines()
    report: dict = json.loads(line)
    return report


def steps_by_name(report: dict) -> dict[str, dict]:
    assert [step["name"] for step in report["steps"]] == list(STEPS)
    return {step["name"]: step for step in report["steps"]}


def assert_stopped_after(report: dict, failed: str) -> dict:
    """Steps before ``failed`` ok, ``failed`` failed with a hint, later ones not tried."""
    steps = steps_by_name(report)
    at = STEPS.index(failed)
    for name in STEPS[:at]:
        assert steps[name]["ok"] is True, steps[name]
        assert steps[name]["hint"] is None
    step = steps[failed]
    assert step["ok"] is False and step["hint"], step
    for name in STEPS[at + 1 :]:
        assert steps[name] == {
            "name": name,
            "ok": None,
            "seconds": None,
            "detail": "not tried",
            "problem": None,
            "hint": None,
        }
    assert report["ok"] is False
    return step


@pytest.fixture
def session_server() -> Iterator[Callable[[Sessions], RecordingServer]]:
    """A RAC server that answers every line ``0,3,123`` and keeps one session: ``"one"``
    closes (resets) any connection made while one is open; ``"newest"`` closes the open
    one when another comes and serves the newcomer."""
    servers: list[RecordingServer] = []

    def make(sessions: Sessions) -> RecordingServer:
        servers.append(RecordingServer(fixed_reply(ANSWER), sessions=sessions))
        return servers[-1]

    yield make
    for server in servers:
        server.close()


@pytest.fixture
def recording() -> Iterator[Callable[[bytes | None], RecordingServer]]:
    servers: list[RecordingServer] = []

    def make(answer: bytes | None) -> RecordingServer:
        servers.append(RecordingServer(lambda line: answer))
        return servers[-1]

    yield make
    for server in servers:
        server.close()


# ------------------------------------------------- the CLI: the simulator (no -H)


@pytest.mark.slow
def test_the_simulator_passes_every_step(env: dict[str, str]) -> None:
    result = cli(env, "check", "--json")
    assert result.returncode == 0, result.stderr
    report = report_of(result)
    assert report["ok"] is True and report["status"] == 0
    assert report["simulator"] is True and report["profile"] is None
    for step in steps_by_name(report).values():
        assert step["ok"] is True, step
        assert step["hint"] is None and step["problem"] is None
        assert isinstance(step["seconds"], float) and 0 <= step["seconds"] < 5
    steps = steps_by_name(report)
    assert "GET:RC8:0:I: answered 0,3," in steps["get"]["detail"]
    assert "median" in steps["round_trip"]["detail"] and "max" in steps["round_trip"]["detail"]
    assert "built-in RC8 simulator" in result.stderr  # said, as every command says it


@pytest.mark.slow
def test_the_text_says_it_checks_the_simulator_one_line_a_step(
    env: dict[str, str],
) -> None:
    result = cli(env, "check", "--read-only")  # only GETs: read-only changes nothing
    assert result.returncode == 0, result.stderr
    heading, *lines = result.stdout.splitlines()
    assert heading.startswith("checking the built-in simulator at 127.0.0.1:")
    assert "no -H" in heading
    assert [line.split()[0] for line in lines] == ["resolve", "connect", "RAC", "round", "second"]
    assert all(" ok " in line for line in lines), lines


# ------------------------------------------------ the CLI: what fails, and why


@pytest.mark.slow
def test_a_closed_port_is_refused_and_names_the_port_and_the_rac_server(
    env: dict[str, str],
) -> None:
    port = unused_port()
    result = cli(env, "check", "-H", "127.0.0.1", "-p", str(port), "--json")
    assert result.returncode == 3, result.stderr
    step = assert_stopped_after(report_of(result), "connect")
    assert step["problem"] == "refused"
    assert f"127.0.0.1:{port}: Connection refused" in step["detail"]
    assert f"port {port}" in step["hint"] and "RAC server option" in step["hint"]
    assert "5006" in step["hint"]
    text = cli(env, "check", "-H", "127.0.0.1", "-p", str(port))
    assert text.returncode == 3
    [connect] = [line for line in text.stdout.splitlines() if line.startswith("connect")]
    assert "FAILED" in connect and "RAC server option" in connect
    assert [line.split()[-2:] for line in text.stdout.splitlines()[3:]] == [["not", "tried"]] * 3


@pytest.mark.slow
def test_a_name_that_does_not_resolve_stops_at_the_first_step(
    env: dict[str, str],
) -> None:
    result = cli(env, "check", "-H", "robot9.invalid", "--json")
    assert result.returncode == 3, result.stderr
    step = assert_stopped_after(report_of(result), "resolve")
    assert step["detail"].startswith("robot9.invalid: ")
    assert step["problem"] in ("unknown host", "dns timeout")
    assert "DNS" in step["hint"] and "IP address" in step["hint"]


@pytest.mark.slow
def test_a_controller_that_keeps_one_session_fails_the_second_session(
    env: dict[str, str],
    session_server: Callable[[Sessions], RecordingServer],
) -> None:
    server = session_server("one")
    result = cli(env, "check", *server.args, "--json")
    assert result.returncode == 3, result.stderr
    step = assert_stopped_after(report_of(result), "second_session")
    assert step["detail"].startswith("a second connection, opened with the first still open: ")
    assert "another client" in step["hint"] and "one session at a time" in step["hint"]
    assert server.turned_away >= 1
    assert set(server.lines) == {GET_I0}  # GETs only


@pytest.mark.slow
def test_a_controller_that_pushes_the_first_session_out_is_said_so(
    env: dict[str, str],
    session_server: Callable[[Sessions], RecordingServer],
) -> None:
    server = session_server("newest")
    result = cli(env, "check", *server.args, "--json")
    assert result.returncode == 3, result.stderr
    step = assert_stopped_after(report_of(result), "second_session")
    assert step["problem"] == "displaced", step
    assert step["detail"].startswith("the first connection, after the second opened: ")
    assert "pushed the first one out" in step["hint"]


@pytest.mark.slow
def test_a_server_that_never_answers_fails_the_get_within_the_timeout(
    env: dict[str, str],
    recording: Callable[[bytes | None], RecordingServer],
) -> None:
    server = recording(None)
    result = cli(env, "check", *server.args, "--timeout", "0.5", "--json")
    assert result.returncode == 3, result.stderr
    step = assert_stopped_after(report_of(result), "get")
    assert step["problem"] == "no answer"
    assert step["detail"] == "the GET (GET:RC8:0:I:): no reply within 0.5 s"
    assert "RAC server option" in step["hint"] and "--timeout" in step["hint"]
    assert step["seconds"] >= 0.5  # it waited its timeout (cli()'s own bounds a hang)
    assert server.lines == [GET_I0]


@pytest.mark.slow
def test_an_error_to_the_get_is_exit_1(
    env: dict[str, str],
    recording: Callable[[bytes | None], RecordingServer],
) -> None:
    server = recording(E_ACCESSDENIED)
    result = cli(env, "check", *server.args, "--json")
    assert result.returncode == 1, result.stderr
    step = assert_stopped_after(report_of(result), "get")
    assert step["problem"] == "error" and "E_ACCESSDENIED" in step["detail"]
    assert "the connection and RAC work" in step["hint"]


@pytest.mark.slow
def test_a_read_only_profile_is_checked_by_name_with_gets_only(
    env: dict[str, str],
    recording: Callable[[bytes | None], RecordingServer],
    tmp_path: Path,
) -> None:
    server = recording(ANSWER)
    config = tmp_path / "config.toml"
    config.write_text(
        f'[target.cell3]\nhost = "127.0.0.1"\nport = {server.port}\nwrites = "read-only"\n',
        encoding="utf-8",
    )
    env = dict(env, RAC_CONSOLE_CONFIG=str(config))
    result = cli(env, "check", "-H", "cell3", "--read-only")
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.splitlines()[0] == f"checking 127.0.0.1:{server.port} (profile cell3)"
    assert set(server.lines) == {GET_I0} and len(server.lines) == 8  # 1 + 5 + 2
    as_json = report_of(cli(env, "check", "-H", "cell3", "--json"))
    assert as_json["profile"] == "cell3" and as_json["port"] == server.port


@pytest.mark.slow
def test_check_records_its_frames_with_record(
    env: dict[str, str],
    tmp_path: Path,
) -> None:
    record = tmp_path / "check.jsonl"
    result = cli(env, "check", "--record", str(record))
    assert result.returncode == 0, result.stderr
    frames = [json.loads(line) for line in record.read_text().splitlines()]
    assert [f["text"] for f in frames if f["dir"] == "tx"] == ["GET:RC8:0:I:"] * 8


# ---------------------------------------- the pointers to check from other failures


@pytest.mark.slow
def test_the_console_points_to_check_when_it_cannot_connect_at_start() -> None:
    port = unused_port()
    engine = Engine("127.0.0.1", port, interval=0.05, timeout=0.5)
    engine.start()
    try:
        front = Front(engine)
        front.until(lambda: 0 in front.results, "the start's connection failure")
        [said] = [f.text for f in front.results[0].feedback]  # type: ignore[union-attr]
        assert said == (
            f"cannot connect to 127.0.0.1:{port}: Connection refused: commands will retry "
            f"(rac-console check -H 127.0.0.1 -p {port} says why)"
        )
        [error] = front.errors(f"connect 127.0.0.1:{port}")
        assert f"(rac-console check -H 127.0.0.1 -p {port} says why)" in error
        [error] = front.errors("connect robot9.invalid")
        assert "(rac-console check -H robot9.invalid says why)" in error
    finally:
        engine.stop()


@pytest.mark.slow
def test_a_write_whose_first_read_fails_points_to_check_not_to_no_verify(
    env: dict[str, str],
    recording: Callable[[bytes | None], RecordingServer],
) -> None:
    server = recording(None)
    result = cli(env, "put", "I", "10", "5", *server.args, "--timeout", "0.5")
    assert result.returncode == 3
    assert "PUT I10 not sent: reading its value first failed: no reply within 0.5 s" in (
        result.stderr
    )
    assert f"(rac-console check -H 127.0.0.1 -p {server.port} says why)" in result.stderr
    assert "--no-verify" not in result.stderr
    assert server.lines == [b"GET:RC8:10:I:"]  # no PUT went out


def test_a_name_server_that_never_answers_is_given_up_on_in_time(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from rac_console.session import diagnose as probe

    release = threading.Event()

    def stuck(*args: object, **kwargs: object) -> list[object]:
        release.wait(10)  # a name server that does not answer (released when the test ends)
        raise socket.gaierror(socket.EAI_AGAIN, "Temporary failure in name resolution")

    monkeypatch.setattr(socket, "getaddrinfo", stuck)
    try:
        # The stuck lookup is released only after this returns: returning is giving up.
        report = probe.diagnose("robot3.plant", 5006, timeout=0.5, resolve_within=0.2)
    finally:
        release.set()
    resolve = report.steps[0]
    assert (resolve.ok, resolve.problem) == (False, "dns timeout")
    assert resolve.detail == "robot3.plant: no answer from the name server within 0.2 s"
    assert "name server did not answer" in (hint(resolve, report) or "")
    assert report.status == ExitStatus.TRANSPORT
    assert [step.ok for step in report.steps[1:]] == [None] * 4


# ------------------------------------------------- the words (pure), and the table


def _report(*steps: StepResult, port: int = 5006) -> CheckReport:
    return CheckReport.of("10.0.0.5", port, list(steps), 2.0)


@pytest.mark.parametrize(
    "step, problem, words",
    [
        ("resolve", "unknown host", "DNS"),
        ("resolve", "dns timeout", "name server did not answer"),
        ("connect", "refused", "RAC server option"),
        ("connect", "timed out", "subnet"),
        ("connect", "unreachable", "cable"),
        ("connect", "closed", "another client"),
        ("get", "no answer", "--timeout 2"),
        ("get", "bad reply", "not in RAC"),
        ("get", "error", "the connection and RAC work"),
        ("round_trip", "closed", "another client"),
        ("second_session", "refused", "another client"),
        ("second_session", "no answer", "one session at a time"),
        ("second_session", "displaced", "pushed the first one out"),
    ],
)
def test_each_failure_has_its_hint(step: str, problem: str, words: str) -> None:
    failed = StepResult(step, False, 0.1, "what happened", problem)  # type: ignore[arg-type]
    report = _report(failed)
    said = hint(failed, report)
    assert said is not None and words in said
    line = step_line(failed, report)
    assert line.startswith(TITLES[failed.name]) and line.endswith(f"FAILED  what happened — {said}")


def test_the_status_is_3_for_a_connection_step_and_1_for_an_answered_error() -> None:
    ok = [StepResult(name, True, 0.001, "fine") for name in STEPS]
    assert _report(*ok).status == ExitStatus.OK
    refused = StepResult("connect", False, 0.001, "refused", "refused")
    assert _report(ok[0], refused).status == ExitStatus.TRANSPORT
    second = StepResult("second_session", False, 0.001, "closed", "closed")
    assert _report(*ok[:4], second).status == ExitStatus.TRANSPORT
    error = StepResult("get", False, 0.001, "E_ACCESSDENIED", "error")
    report = _report(*ok[:2], error)
    assert report.status == ExitStatus.CONTROLLER_ERROR
    data = report_json(report, "cell3", False)
    assert data["status"] == 1 and data["ok"] is False and data["profile"] == "cell3"
    assert [s["ok"] for s in data["steps"]] == [True, True, False, None, None]


def test_a_name_that_is_no_profile_either_is_said_with_the_resolution_hint() -> None:
    failed = StepResult("resolve", False, 0.01, "cel3: host not found", "unknown host")
    said = hint(failed, _report(failed), "no profile named cel3 in /x/config.toml")
    assert said is not None and said.endswith("(no profile named cel3 in /x/config.toml)")


def test_the_pointer_names_the_port_only_when_it_is_not_5006() -> None:
    assert check_pointer("10.0.0.5", 5006) == "(rac-console check -H 10.0.0.5 says why)"
    assert check_pointer("cell3", None) == "(rac-console check -H cell3 says why)"
    assert check_pointer("10.0.0.5", 5007) == "(rac-console check -H 10.0.0.5 -p 5007 says why)"
    assert check_pointer("my robot", 5006) == "(rac-console check -H 'my robot' says why)"
    assert check_pointer(None) == "(rac-console check says why)"


def _windows(cls: type[OSError], code: int, text: str) -> OSError:
    """An exception as Windows raises it: errno and winerror both the WinSock code."""
    exc = cls(code, text)
    exc.winerror = code  # type: ignore[attr-defined]
    return exc


@pytest.mark.parametrize(
    "exc, words, problem",
    [
        (
            _windows(
                ConnectionRefusedError,
                10061,
                "No connection could be made because the target machine actively refused it",
            ),
            "Connection refused",
            "refused",
        ),
        (OSError(10061, "No connection could be made"), "Connection refused", None),
        (_windows(TimeoutError, 10060, "A connection attempt failed"), "timed out", "timed out"),
        (OSError(10060, "A connection attempt failed"), "timed out", None),
        (
            _windows(OSError, 10065, "A socket operation was attempted"),
            "No route to host",
            "unreachable",
        ),
        (_windows(OSError, 10051, "A socket operation"), "Network is unreachable", "unreachable"),
        (socket.gaierror(11001, "getaddrinfo failed"), "host not found", "unknown host"),
        (socket.gaierror(11004, "The requested name is valid"), "host not found", "unknown host"),
        # and Linux's own, worded the same
        (
            ConnectionRefusedError(errno.ECONNREFUSED, "Connection refused"),
            "Connection refused",
            "refused",
        ),
        (TimeoutError(errno.ETIMEDOUT, "Connection timed out"), "timed out", "timed out"),
        (OSError(errno.EHOSTUNREACH, "No route to host"), "No route to host", "unreachable"),
        (
            socket.gaierror(socket.EAI_NONAME, "Name or service not known"),
            "host not found",
            "unknown host",
        ),
    ],
)
def test_socket_errors_are_worded_alike_on_windows_and_linux(
    exc: OSError, words: str, problem: str | None
) -> None:
    assert _reason(exc) == words
    if problem is not None:
        assert _problem(exc) == problem


def test_a_winsock_code_outside_the_table_keeps_the_exceptions_own_words() -> None:
    text = "An attempt was made to access a socket in a way forbidden by its access permissions"
    said = _reason(_windows(PermissionError, 10013, text))
    assert said == text and "Unknown error" not in said


# ------------------------------------- real network paths (namespaces, optional)


def _namespaces_unavailable() -> str | None:
    if sys.platform != "linux" or os.geteuid() != 0:
        return "needs root on Linux"
    if shutil.which("ip") is None:
        return "needs ip"
    return None


@pytest.fixture
def blackhole() -> Iterator[str]:
    """A network namespace whose only network is 10.79.0.0/24 on one end of a veth pair,
    with 10.79.0.2 pinned to a MAC nobody has: a SYN to it goes out and is never
    answered (a pulled cable, a firewall that drops), and 10.80.0.2 has no route."""
    why = _namespaces_unavailable()
    if why:
        pytest.skip(f"network namespaces: {why}")
    namespace = f"rcheck{os.getpid() % 100000}"
    made = subprocess.run(["ip", "netns", "add", namespace], capture_output=True, timeout=20)
    if made.returncode:
        pytest.skip(f"network namespaces: ip netns add failed: {made.stderr.decode().strip()}")
    try:
        for words in (
            ["link", "set", "lo", "up"],
            ["link", "add", "v0", "type", "veth", "peer", "name", "v1"],
            ["addr", "add", "10.79.0.1/24", "dev", "v0"],
            ["link", "set", "v0", "up"],
            ["link", "set", "v1", "up"],
            ["neigh", "add", "10.79.0.2", "lladdr", "02:00:00:00:00:02", "dev", "v0"],
        ):
            subprocess.run(["ip", "-n", namespace, *words], check=True, timeout=20)
        yield namespace
    finally:
        subprocess.run(["ip", "netns", "del", namespace], capture_output=True, timeout=20)


def _check_in(
    namespace: str, environment: dict[str, str], *args: str
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        ["ip", "netns", "exec", namespace, sys.executable, "-m", "rac_console", "check", *args],
        env=environment,
        capture_output=True,
        text=True,
        timeout=30,
    )


@pytest.mark.slow
def test_a_controller_that_never_answers_the_connect_times_out(
    blackhole: str,
    env: dict[str, str],
) -> None:
    result = _check_in(blackhole, env, "-H", "10.79.0.2", "--timeout", "0.5", "--json")
    assert result.returncode == 3, result.stderr
    step = assert_stopped_after(report_of(result), "connect")
    assert step["problem"] == "timed out" and step["detail"].endswith("timed out")
    assert "cable" in step["hint"] and "subnet" in step["hint"] and "firewall" in step["hint"]
    assert step["seconds"] >= 0.5  # it waited its timeout


@pytest.mark.slow
def test_an_address_with_no_route_says_cable_address_and_subnet(
    blackhole: str,
    env: dict[str, str],
) -> None:
    result = _check_in(blackhole, env, "-H", "10.80.0.2", "--json")
    assert result.returncode == 3, result.stderr
    step = assert_stopped_after(report_of(result), "connect")
    assert step["problem"] == "unreachable", step
    assert step["detail"].endswith("Network is unreachable")
    assert "cable" in step["hint"] and "subnet" in step["hint"]
