"""Output never fails on an encoding (issue 21, items 1 and 4): a Windows pipe or file
gets the ANSI code page (cp1252, cp437, cp932), which has no ``→`` or ``✓``. Tried here
with PYTHONIOENCODING, the CLI as a subprocess, its bytes read as that code page."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

CODE_PAGES = ["cp1252", "cp437", "cp932"]


def _run(
    base: dict[str, str], encoding: str, *args: str, stdin: bytes = b""
) -> tuple[int, str, str]:
    environment = dict(base, PYTHONIOENCODING=encoding)
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", *args],
        env=environment,
        input=stdin,
        capture_output=True,
        timeout=30,
    )
    out = result.stdout.decode(encoding)  # must be that code page, whole
    err = result.stderr.decode(encoding)
    assert "Traceback" not in out + err, err
    return result.returncode, out, err


@pytest.mark.parametrize("encoding", CODE_PAGES)
def test_a_put_to_a_code_page_pipe_says_what_happened(
    encoding: str,
    env: dict[str, str],
) -> None:
    status, out, err = _run(env, encoding, "put", "I", "10", "15")
    assert status == 0, err
    assert out.startswith("I10: 0 -> 15  S_OK  read back 15 [ok]"), out


@pytest.mark.parametrize("encoding", CODE_PAGES)
def test_run_get_watch_and_the_repl_write_to_a_code_page(
    encoding: str,
    env: dict[str, str],
) -> None:
    script = b"put I 10 15\nget S 1\nput S 2 abc\n"
    for args in (["run", "-"], ["repl"]):  # the REPL with no terminal runs the script
        status, out, err = _run(env, encoding, *args, stdin=script)
        assert status == 0, err
        assert "-> 15" in out and '"RC8 simulator"' in out and "[ok]" in out, out
    status, out, err = _run(env, encoding, "get", "P", "1")
    assert status == 0 and out.startswith("P1 = X"), (out, err)
    status, out, err = _run(env, encoding, "watch", "I", "1", "--count", "1")
    assert status == 0 and "I1=" in out, (out, err)


def test_json_stays_ascii(env: dict[str, str]) -> None:
    status, out, err = _run(env, "cp1252", "put", "S", "3", "x", "--json")
    assert status == 0, err
    assert out.isascii()
    assert json.loads(out)["verified"] is True


def test_a_utf8_script_from_a_pipe_is_read_as_utf8(env: dict[str, str]) -> None:
    script = "\ufeffget I 1\nput S 1 café\n".encode()  # UTF-8 with a BOM, as Notepad saves
    status, out, err = _run(env, "cp1252", "run", "-", stdin=script)
    assert "I1 = " in out, (out, err)
    assert "'é' cannot be sent" in err, err  # the character as typed, not mojibake
    assert status == 2


# ------------------------------------------- a config saved by PowerShell or Notepad


def _profile_file(tmp_path: Path, data: bytes) -> Path:
    path = tmp_path / "config.toml"
    path.write_bytes(data)
    return path


CONFIG = '[target.cell3]\nhost = "127.0.0.1"\nlabel = "Zelle 3 — Schweißen"\n'


def test_a_config_saved_as_utf16_by_powershell_is_read(tmp_path: Path) -> None:
    from rac_console.engine.setup.config import load_config

    for encoding in ("utf-16", "utf-16-be"):
        data = (
            ("\ufeff" + CONFIG).encode(encoding)
            if encoding.endswith("be")
            else CONFIG.encode(encoding)
        )
        config = load_config(_profile_file(tmp_path, data))
        assert config.profiles["cell3"].label == "Zelle 3 — Schweißen"


def test_a_config_in_ansi_says_what_it_looks_like_and_how_to_save_it(tmp_path: Path) -> None:
    from rac_console.engine.setup.config import load_config
    from rac_console.protocol import InputError

    with pytest.raises(InputError, match=r"looks like ANSI .* save it as UTF-8"):
        load_config(_profile_file(tmp_path, CONFIG.encode("cp1252")))
    with pytest.raises(InputError, match="UTF-16 without a byte order mark"):
        load_config(_profile_file(tmp_path, CONFIG.encode("utf-16-le")))
