"""Reading the small text files a user names (a watch list, the config file): one line
for anything that is not one, never a traceback, and never an endless read."""

from __future__ import annotations

from pathlib import Path

from ..protocol import InputError

#: A file larger than this is not one of ours: refused before it is parsed.
MAX_FILE_BYTES = 1024 * 1024


#: The byte order mark Notepad on Windows has written at the start of UTF-8 files.
BOM = "\ufeff"


def read_text_file(
    path: Path, what: str, shown: str | Path | None = None, *, keep_bom: bool = False
) -> str:
    """The UTF-8 text of the regular file ``path`` (a leading BOM dropped, unless
    ``keep_bom``: a writer puts it back); InputError naming it as ``shown`` (the path as
    the user gave it) and saying it is not ``what`` ("a watch list")."""
    shown = path if shown is None else shown
    try:
        if path.exists() and not path.is_file():  # a device or a pipe: endless, or no end
            raise InputError(f"{shown} is not a regular file: not {what}")
        with path.open("rb") as handle:
            data = handle.read(MAX_FILE_BYTES + 1)
        if len(data) > MAX_FILE_BYTES:
            raise InputError(f"{shown} is larger than {MAX_FILE_BYTES // 1024} KiB: not {what}")
        text = data.decode("utf-8")
        return text if keep_bom else text.removeprefix(BOM)
    except (OSError, RuntimeError) as exc:
        raise InputError(f"cannot read {shown}: {getattr(exc, 'strerror', None) or exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"{shown} is not a UTF-8 text file") from None
