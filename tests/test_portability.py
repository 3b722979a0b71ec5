"""What differs on Windows, checked where it can be on any system (issue 21): the extra
that has no Windows build, and the paths docs/windows.md gives."""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement

from tests.support.drivers import cli

ROOT = Path(__file__).resolve().parent.parent


def test_the_fast_extra_installs_nothing_on_windows() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    for text in project["optional-dependencies"]["fast"]:
        requirement = Requirement(text)
        assert requirement.marker is not None, text  # uvloop has no Windows build
        assert not requirement.marker.evaluate({"sys_platform": "win32"})
        assert requirement.marker.evaluate({"sys_platform": "linux"})


@pytest.mark.slow
def test_paths_says_where_the_config_is_as_the_readme_does(env: dict[str, str]) -> None:
    env.pop("RAC_CONSOLE_CONFIG", None)
    result = cli(env, "paths")
    assert result.returncode == 0, result.stderr
    config = result.stdout.splitlines()[0]
    doc = (ROOT / "docs" / "windows.md").read_text(encoding="utf-8")
    assert "%LOCALAPPDATA%\\rac-console\\rac-console\\config.toml" in doc
    if sys.platform == "win32":
        assert "rac-console\\rac-console\\config.toml" in config, config
    else:
        assert config.endswith("rac-console/config.toml, not there yet"), config
        assert env["XDG_CONFIG_HOME"] in config or sys.platform == "darwin"


def _as_a_user_would(*args: str, stdin: bytes = b"") -> tuple[int, str, str]:
    """The CLI with no encoding setting at all: on Windows a pipe then gets the ANSI
    code page (cp1252), as a user's ``> out.txt`` does. Not marked slow, so the Windows
    lane runs it."""
    import locale
    import os
    import subprocess

    environment = {
        key: value
        for key, value in os.environ.items()
        if key not in ("PYTHONIOENCODING", "PYTHONUTF8", "COLUMNS", "LINES")
    }
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", *args],
        env=environment,
        input=stdin,
        capture_output=True,
        timeout=60,
    )
    encoding = locale.getpreferredencoding(False)
    out, err = result.stdout.decode(encoding), result.stderr.decode(encoding)
    assert "Traceback" not in out + err, err
    return result.returncode, out, err


def test_a_piped_put_with_no_setting_says_what_happened() -> None:
    status, out, err = _as_a_user_would("put", "I", "10", "15")
    assert status == 0, err
    assert out.startswith("I10: 0 ") and "read back 15" in out, out


def test_a_piped_utf8_script_with_no_setting_is_read_as_utf8() -> None:
    status, out, err = _as_a_user_would("run", "-", stdin="get I 1\nput S 1 café\n".encode())
    assert status == 2, err  # the non-ASCII value is refused, the rest ran
    assert "I1 = " in out, (out, err)
    assert "'é' cannot be sent" in err, err
