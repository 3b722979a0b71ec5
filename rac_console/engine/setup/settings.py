"""The settings kept in the config file's ``[settings]`` table: read, and written back.

What goes in the table and how its text is rewritten is pure
(:mod:`rac_console.commands.settings`); here is the file. A save reads the file as it is
now (the user may have edited it meanwhile), changes only the ``[settings]`` lines, and
replaces it atomically: a temporary file in the same directory, then ``os.replace``, so
that a crash or a full disk never leaves half a file. The file keeps its mode; a new one
is owner-only, in a directory made owner-only. A symlinked file (dotfiles) is written
where the link points, and stays a link. Every failure is an InputError of one line
naming the file.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Collection, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from ...protocol.errors import InputError
from ..files.textfile import BOM, read_text_file
from .config import load_config

if TYPE_CHECKING:
    from ...commands.settings import Value


@dataclass(frozen=True)
class LoadedSettings:
    """The settings the file holds (known keys with the right types), and a line for
    each one ignored."""

    values: dict[str, Value] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)


class SettingsFile:
    """The config file at ``path``, as far as its ``[settings]`` go."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def load(self, themes: Collection[str] | None = None) -> LoadedSettings:
        """The settings (a theme only among ``themes``, when given); InputError (one
        line) when the file cannot be read or parsed."""
        config = load_config(self.path)
        if not config.settings:
            return LoadedSettings()  # no [settings]: their rules need not load (the start)
        from ...commands.settings import read_settings

        values, problems = read_settings(config.settings, str(self.path), themes)
        return LoadedSettings(values, problems)

    def can_write(self) -> None:
        """Whether the file could be made (its folder made, none in the way): InputError
        of one line when not. Nothing is written."""
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            if not os.access(self.path.parent, os.W_OK):
                raise PermissionError(13, "Permission denied")
        except OSError as exc:
            reason = exc.strerror or str(exc)
            raise InputError(f"cannot write {self.path}: {reason}") from None

    def save(self, values: Mapping[str, Value]) -> None:
        """Set ``values`` in the file's ``[settings]``, keeping every other byte;
        InputError (one line) when it cannot, the file then left as it was."""
        path = self.path
        from ...commands.settings import update_settings_text

        real = Path(os.path.realpath(path))  # a symlink's target: the link stays
        try:
            text, mode = _read(real, path)
            bom = BOM if text.startswith(BOM) else ""  # kept, as every other byte
            new = update_settings_text(text.removeprefix(BOM), values, str(path))
            _replace(real, (bom + new).encode("utf-8"), mode)
        except UnicodeDecodeError:
            raise InputError(f"{path} is not a UTF-8 text file") from None
        except OSError as exc:
            reason = exc.strerror or str(exc)
            raise InputError(f"cannot write {path}: {reason}") from None


def _read(path: Path, shown: Path) -> tuple[str, int | None]:
    """The file's text and mode; ``""`` and None when there is no file. Messages name
    it as ``shown`` (the path as the user gave it)."""
    try:
        info = path.stat()
    except FileNotFoundError:
        return "", None
    return read_text_file(path, "a config file", shown, keep_bom=True), stat.S_IMODE(info.st_mode)


def _replace(path: Path, data: bytes, mode: int | None) -> None:
    """Write ``data`` to a temporary file beside ``path``, then put it in its place."""
    directory = path.parent
    directory.mkdir(mode=0o700, parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=directory, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "wb") as out:
            out.write(data)
            out.flush()
            os.fsync(out.fileno())
        os.chmod(temporary, 0o600 if mode is None else mode)
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise
