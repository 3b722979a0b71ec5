"""Reading the small text files a user names (a watch list, the config file): one line
for anything that is not one, never a traceback, and never an endless read."""

from __future__ import annotations

from pathlib import Path

from ...protocol import InputError

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
        text = _decoded(data)
        return text if keep_bom else text.removeprefix(BOM)
    except (OSError, RuntimeError) as exc:
        raise InputError(f"cannot read {shown}: {getattr(exc, 'strerror', None) or exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"{shown} {_looks_like(data)}") from None


#: How to save a file as UTF-8, said with a refusal.
SAVE_AS_UTF8 = (
    "save it as UTF-8 (Notepad: Save as, Encoding UTF-8; PowerShell: Set-Content -Encoding utf8)"
)


def _decoded(data: bytes) -> str:
    """UTF-8, or UTF-16 with its byte order mark (what PowerShell 5's ``>`` writes); the
    text keeps a leading BOM either way (a writer puts it back, as UTF-8)."""
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        return BOM + data.decode("utf-16")  # the codec takes the mark: put back as one
    return data.decode("utf-8")


def _looks_like(data: bytes) -> str:
    """Why a file is not UTF-8, in words: what it looks like, and how to fix it."""
    if b"\x00" in data[:256]:
        return (
            "is not a UTF-8 text file: it looks like UTF-16 without a byte order mark; "
            + SAVE_AS_UTF8
        )
    return f"is not a UTF-8 text file: it looks like ANSI (Windows-1252) text; {SAVE_AS_UTF8}"
