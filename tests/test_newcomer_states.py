"""What the status line says when nothing is connected (issue 20, items 2 and 9): a
target that refuses is called refused, never ``idle`` (which reads as healthy), and a
connection that never opened is not called lost or closed."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.engine import Engine
from rac_console.present.status import status_text
from tests.support.drivers import Front, cli, one_error_line, profile
from tests.support.servers import RecordingServer, unused_port


def _line(front: Front) -> str:
    assert front.status is not None
    return status_text(front.status, None, 0.0).plain


def test_a_target_nobody_listens_on_is_called_refused() -> None:
    port = unused_port()
    engine = Engine("127.0.0.1", port, interval=0.05, timeout=1.0)
    engine.start()
    try:
        front = Front(engine)
        front.until(
            lambda: front.status is not None and front.status.connection == "refused",
            "the refusal on the status line",
        )
        line = _line(front)
        assert "connection refused" in line and "idle" not in line, line
    finally:
        engine.stop()


def test_connect_to_nobody_while_watching_is_not_a_lost_connection(front: Front) -> None:
    front.run("watch I 1")
    port = unused_port()
    said = " ".join(front.run(f"connect 127.0.0.1:{port}"))
    assert "refused" in said.lower(), said
    front.until(
        lambda: (
            front.status is not None
            and front.status.connection == "refused"
            and front.status.retry_at is not None
        ),
        "the poller's retry countdown",
    )
    line = _line(front)
    assert "connection refused, retrying in" in line and "lost" not in line, line
    assert not any("good exchanges" in note for note in front.notes), front.notes
    assert not any(note.startswith("connection lost") for note in front.notes), front.notes


def test_a_target_that_never_answered_is_not_connected_yet() -> None:
    port = unused_port()
    engine = Engine("127.0.0.1", port, interval=0.05, timeout=1.0)
    engine.start(connect=False)
    try:
        front = Front(engine)
        front.until(lambda: front.status is not None, "a status")
        assert "not connected yet" in _line(front), _line(front)
    finally:
        engine.stop()


def test_after_disconnect_the_hint_names_connect_sim(front: Front) -> None:
    [said] = front.run("disconnect")
    assert "connect sim" in said
    [error] = front.errors("get I 1")
    assert "connect sim" in error


# ------------------------------------------- a read-only refusal names what it refused


@pytest.mark.slow
def test_a_read_only_refusal_names_what_it_refused(
    env: dict[str, str],
    config: Callable[[str], Path],
    recording: Callable[..., RecordingServer],
) -> None:
    server = recording()
    config(profile("ro", server.port, 'writes = "read-only"'))
    raw = cli(env, "-H", "ro", "send", "SIM:GET:")
    assert raw.returncode == 2
    line = one_error_line(raw)
    assert "PUT" not in line and "'SIM:GET:' refused: profile ro is read-only" in line, line
    typed = cli(env, "-H", "ro", "put", "I", "10", "5")
    assert "PUT I10 refused: profile ro is read-only" in one_error_line(typed)
    other = recording()  # no profile there: the flag's own rule
    flag = cli(env, "--read-only", "-H", "127.0.0.1", "-p", str(other.port), "send", "X")
    assert "'X' refused: read-only mode is on" in one_error_line(flag)
    assert bytes(server.received) == bytes(other.received) == b""


# ------------------------------------------------ output to a pipe is never wrapped


@pytest.mark.slow
def test_output_to_a_pipe_is_never_wrapped(env: dict[str, str]) -> None:
    env["COLUMNS"] = "80"
    latency = cli(env, "latency", "--count", "20")
    assert latency.returncode == 0, latency.stderr
    assert len(latency.stdout.splitlines()) == 1, latency.stdout
    long = "x" * 150
    script = f"put S 1 {long}\nget S 1\nget P 1\n"
    run = cli(env, "run", "-", stdin=script)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert len(lines) == 3, lines
    assert long in lines[0] and long in lines[1]


# ------------------------------------------------------ strings that can be seen


@pytest.mark.slow
def test_strings_in_results_show_empty_and_spaces(env: dict[str, str]) -> None:
    script = 'put S 10 ""\nget S 10\nput S 11 "  two  "\nget S 11\nput S 12 say "hi"\n'
    result = cli(env, "run", "-", stdin=script)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith('S10: "" → ""  S_OK  read back "" ✓'), lines
    assert lines[1].startswith('S10 = ""'), lines
    assert lines[3].startswith('S11 = "  two  "'), lines
    assert 'read back "say \\"hi\\"" ✓' in lines[4], lines


# ------------------------- the profile example (docs/targets.md) works as printed


PROFILES_DOC = Path(__file__).resolve().parent.parent / "docs" / "targets.md"


@pytest.mark.slow
def test_the_readmes_simulator_profile_works_as_printed(
    env: dict[str, str],
    config: Callable[[str], Path],
) -> None:
    import tomllib

    from rac_console.commands.profiles import parse_config
    from rac_console.sim.thread import SimulatorThread

    text = PROFILES_DOC.read_text(encoding="utf-8")
    block = text.split("```toml\n[target.bench]\n", 1)[1].split("```", 1)[0]
    example = "[target.bench]\n" + block
    bench = parse_config(tomllib.loads(example), "docs/targets.md").profiles["bench"]
    assert bench.policy.allow is not None
    with SimulatorThread() as sim:
        config(example.replace("port = 5007", f"port = {sim.port}"))
        for rule in bench.policy.allow:  # every allowed variable exists in the simulator
            answer = cli(env, "-H", "bench", "get", rule.kind.code, str(rule.high))
            assert answer.returncode == 0, (rule, answer.stderr)
        asked = cli(env, "-H", "bench", "put", "I", "10", "5")
        assert asked.returncode == 2 and "--yes" in asked.stderr, asked.stderr
        said_yes = cli(env, "-H", "bench", "put", "I", "10", "5", "--yes")
        assert said_yes.returncode == 0, said_yes.stderr
        outside = cli(env, "-H", "bench", "put", "I", "20", "5", "--yes")
        assert outside.returncode == 2 and "allow" in outside.stderr
