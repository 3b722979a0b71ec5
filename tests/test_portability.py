"""What differs on Windows, checked where it can be on any system (issue 21): the extra
that has no Windows build, and the paths the README gives."""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from test_cli import cli, env  # noqa: F401  (fixture)

ROOT = Path(__file__).resolve().parent.parent


def test_the_fast_extra_installs_nothing_on_windows() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    for text in project["optional-dependencies"]["fast"]:
        requirement = Requirement(text)
        assert requirement.marker is not None, text  # uvloop has no Windows build
        assert not requirement.marker.evaluate({"sys_platform": "win32"})
        assert requirement.marker.evaluate({"sys_platform": "linux"})


@pytest.mark.slow
def test_paths_says_where_the_config_is_as_the_readme_does(env: dict[str, str]) -> None:  # noqa: F811
    env.pop("RAC_CONSOLE_CONFIG", None)
    result = cli(env, "paths")
    assert result.returncode == 0, result.stderr
    config = result.stdout.splitlines()[0]
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    if sys.platform == "win32":
        assert "rac-console\\rac-console\\config.toml" in config, config
        assert "%LOCALAPPDATA%\\rac-console\\rac-console\\" in readme
    else:
        assert config.endswith("rac-console/config.toml, not there yet"), config
        assert env["XDG_CONFIG_HOME"] in config or sys.platform == "darwin"
