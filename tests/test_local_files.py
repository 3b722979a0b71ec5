"""Local files: a failing disk is reported once and loses nothing on screen; hostile
watch lists get one clear line; the history file is private and shared safely."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from rac_console.engine.watch.watchlist import load
from rac_console.present.history import History
from rac_console.protocol import InputError
from rac_console.tui.status_bar import StatusBar
from tests.support.drivers import Driver, cli, log_text, make_app, results_text, type_line, until

#: Over half a second each (a terminal app, a subprocess, a timed server):
#: `pytest -m "not slow"` skips them.
pytestmark = pytest.mark.slow

needs_dev_full = pytest.mark.skipif(
    not Path("/dev/full").exists(), reason="a device that is always full (Linux)"
)

GETS = "".join(f"get I {n % 100}\n" for n in range(300))


def _limit_file_size(size: int) -> Callable[[], None]:
    import resource  # POSIX: this test runs only where there is a /dev/full
    import signal

    def limit() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails: EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))

    return limit


def error_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if "simulator" not in line]


# ----------------------------------------------------------------- --record


@needs_dev_full
def test_record_on_a_full_device_is_one_line_and_exit_4(env: dict[str, str]) -> None:
    result = cli(env, "--record", "/dev/full", "run", "-", stdin=GETS)
    assert result.returncode == 4, result.stderr
    assert "Traceback" not in result.stderr
    errors = error_lines(result.stderr)
    assert errors == [
        "rac-console: recording stopped: No space left on device after 0 frames (/dev/full)"
    ]
    assert result.stdout.count(" = ") == 300  # every result still printed


@needs_dev_full
def test_record_that_fails_midway_keeps_whole_lines_and_says_how_many(
    env: dict[str, str],
    tmp_path: Path,
) -> None:
    record = tmp_path / "frames.jsonl"
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "--record", str(record), "--json", "run", "-"],
        env=env,
        input=GETS,
        capture_output=True,
        text=True,
        timeout=60,
        preexec_fn=_limit_file_size(16 * 1024),
    )
    assert result.returncode == 4, result.stderr
    errors = error_lines(result.stderr)
    assert len(errors) == 1 and errors[0].startswith("rac-console: recording stopped: ")
    kept = record.read_text().splitlines()
    assert f"after {len(kept)} frames" in errors[0]
    assert 0 < len(kept) < 600
    assert all(json.loads(line)["dir"] in ("tx", "rx") for line in kept)
    assert len(result.stdout.splitlines()) == 300  # every JSON result still printed


@needs_dev_full
def test_get_with_record_on_a_full_device_still_prints_the_value(
    env: dict[str, str],
) -> None:
    result = cli(env, "--record", "/dev/full", "get", "I", "1")
    assert result.returncode == 4
    assert "I1 = " in result.stdout
    assert len(error_lines(result.stderr)) == 1


@needs_dev_full
async def test_console_reports_a_failing_recorder_once_and_keeps_logging(tmp_path: Path) -> None:
    app = make_app(tmp_path, record="/dev/full")
    async with app.run_test(size=(160, 40)) as pilot:
        for n in range(5):
            await type_line(pilot, f"get I {n}")
        await until(pilot, lambda: "I4 = " in results_text(app), "the gets")
        await until(pilot, lambda: "GET:RC8:4:I:" in log_text(app), "the frames in the log")
        assert results_text(app).count("recording stopped: No space left on device") == 1
        assert "RECORDING STOPPED" in str(app.query_one(StatusBar).render())


@needs_dev_full
async def test_repl_reports_a_failing_recorder_once(tmp_path: Path) -> None:
    driver = Driver(tmp_path, record="/dev/full")

    async def steps(d: Driver) -> None:
        for n in range(3):
            d.type(f"get I {n}\r")
        await d.until(lambda out: "I2 = " in out, "the gets")

    out = await driver.run(steps)
    assert out.count("recording stopped: No space left on device after 0 frames") == 1


# -------------------------------------------------------------- watch lists


def deep_toml(path: Path) -> Path:
    path.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    return path


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("deep", "nested too deeply"),
        ("huge", "larger than"),
        ("rows", "more than"),
        ("binary", "not a UTF-8 text file"),
    ],
)
def test_hostile_watch_list_at_start_is_one_line_and_exit_2(
    env: dict[str, str],
    tmp_path: Path,
    content: str,
    message: str,
) -> None:
    path = tmp_path / "cell.toml"
    if content == "deep":
        deep_toml(path)
    elif content == "huge":
        path.write_text("# " + "x" * (2 * 1024 * 1024) + "\n")
    elif content == "rows":
        path.write_text("".join(f'[[watch]]\ntype = "I"\nindex = {n % 100}\n' for n in range(5000)))
    else:
        path.write_bytes(b"\xff\xfe\x00junk")
    result = cli(env, "--watch", str(path))
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], result.stderr


async def test_console_load_of_a_deep_file_is_one_line(tmp_path: Path) -> None:
    path = deep_toml(tmp_path / "deep.toml")
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await type_line(pilot, f"load {path}")
        await until(pilot, lambda: "nested too deeply" in results_text(app), "the answer")
        assert "internal error" not in results_text(app)


async def test_repl_load_of_a_deep_file_answers_and_goes_on(tmp_path: Path) -> None:
    path = deep_toml(tmp_path / "deep.toml")
    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type(f"load {path}\r")
        await d.until(lambda out: "nested too deeply" in out, "the answer")
        d.type("get I 1\r")
        await d.until(lambda out: "I1 = " in out, "the REPL to go on")

    await driver.run(steps)


# ------------------------------------------------------------------ history


@pytest.mark.skipif(os.name != "posix", reason="file modes are POSIX")
def test_an_existing_history_file_is_made_owner_only(tmp_path: Path) -> None:
    path = tmp_path / "history"
    path.write_text("get I 1\n")
    path.chmod(0o644)
    History(path).append("get I 2")
    assert stat.S_IMODE(path.stat().st_mode) == 0o600


def test_a_history_file_left_long_is_trimmed_at_the_next_run(tmp_path: Path) -> None:
    path = tmp_path / "history"
    path.write_text("".join(f"get I {n}\n" for n in range(5000)))
    history = History(path, limit=1000)
    history.append("get S 1")
    lines = path.read_text().splitlines()
    assert len(lines) == 1000 and lines[-1] == "get S 1" and lines[0] == "get I 4001"


def test_two_consoles_sharing_history_keep_each_others_entries(tmp_path: Path) -> None:
    path = tmp_path / "history"
    first, second = History(path, limit=5), History(path, limit=5)
    appended = []
    for n in range(40):
        writer, name = (first, "a") if n % 2 == 0 else (second, "b")
        line = f"get I {n} # {name}"
        writer.append(line)
        appended.append(line)
    lines = path.read_text().splitlines()
    assert lines == appended[-len(lines) :]  # the newest entries of both, none lost
    assert len(lines) >= 5
    assert History(path, limit=5).entries == appended[-5:]


def test_history_writers_in_two_processes_lose_nothing(tmp_path: Path) -> None:
    path = tmp_path / "history"
    script = (
        "import sys\n"
        "from rac_console.present.history import History\n"
        "h = History(sys.argv[1], limit=20)\n"
        "for n in range(300):\n"
        "    h.append(f'get I {n} # ' + sys.argv[2])\n"
    )
    writers = [
        subprocess.Popen([sys.executable, "-c", script, str(path), name]) for name in ("a", "b")
    ]
    for writer in writers:
        assert writer.wait(timeout=60) == 0
    lines = path.read_text().splitlines()
    assert len(lines) >= 20
    for name in ("a", "b"):
        mine = [int(line.split()[2]) for line in lines if line.endswith(f"# {name}")]
        # What is left of each writer is the end of what it wrote, with no gap.
        assert mine == list(range(300 - len(mine), 300)), (name, mine)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ('[[watch]]\ntype = "I"\nindex = "3"\n', "index is a whole number"),
        ('[[watch]]\ntype = "I"\nindex = 3\ncolour = "red"\n', "unknown key 'colour'"),
        ('[[watch]]\ntype = "I"\nindex = 3\n[[watch]]\ntype = "i"\nindex = 3\n', "repeats I3"),
        ('[[watch]]\ntype = "I"\nindex = 3\nevery = -1\n', "every is 0 to 3600 seconds"),
        ('[[watch]]\ntype = "I"\nindex = 3\nlabel = 5\n', "label is text"),
    ],
)
def test_a_watch_list_is_taken_as_written_or_refused(
    tmp_path: Path, content: str, message: str
) -> None:
    from rac_console.engine.watch.watchlist import load
    from rac_console.protocol import InputError

    path = tmp_path / "cell.toml"
    path.write_text(content)
    with pytest.raises(InputError, match=message):
        load(path)


async def test_save_and_load_keep_labels_and_every(tmp_path: Path) -> None:
    path = tmp_path / "cell.toml"
    first = make_app(tmp_path)
    async with first.run_test(size=(120, 40)) as pilot:
        await type_line(pilot, 'watch P 10 "pick every time" every 2.5')
        await type_line(pilot, "watch IO 128-129 gripper")
        await type_line(pilot, f"save {path}")
        await until(pilot, lambda: "saved 3 watched variables" in results_text(first), "save")
    second = make_app(tmp_path)
    async with second.run_test(size=(120, 40)) as pilot:
        await type_line(pilot, f"load {path}")
        await until(pilot, lambda: "loaded 3 watched variables" in results_text(second), "load")
        rows = {
            str(var): (row.label, row.every) for var, row in second.main_screen.members.rows.items()
        }
        assert rows == {
            "P10": ("pick every time", 2.5),
            "IO128": ("gripper", None),
            "IO129": ("gripper", None),
        }


@pytest.mark.parametrize("content", ["watch = 5", "\x81\xfe\xff", "[watch]\ntype = 'P'\n"])
def test_bad_watch_list_files_give_a_message(tmp_path: Path, content: str) -> None:
    path = tmp_path / "cell.toml"
    path.write_bytes(content.encode("latin-1"))
    if "index" not in content and "type" in content:
        with pytest.raises(InputError, match="no 'index'"):
            load(path)
    else:
        with pytest.raises(InputError):
            load(path)


def test_history_rewrite_ignores_a_stale_temporary_file(tmp_path: Path) -> None:
    path = tmp_path / "history"
    (tmp_path / "history.tmp").write_text("stale1\nstale2\n")
    history = History(path, limit=2)
    for n in range(6):
        history.append(f"cmd{n}")
    assert path.read_text().splitlines()[-2:] == ["cmd4", "cmd5"]
    assert "stale1" not in path.read_text()
