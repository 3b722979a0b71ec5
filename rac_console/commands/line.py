"""How long a line of the command language may be: every front end holds its command line
to it and the registry refuses a longer line whole. Apart from the language (which loads
with the first command), so the console's command line can know it before that.
"""

from __future__ import annotations

from ..protocol.errors import InputError

#: The longest line of the command language, in characters. A RAC frame is at most 256
#: bytes with its CR, but a value is sent as its number, not as typed: a ``put T`` of ten
#: values each written out in full decimal (the smallest VT_R4, ``-0.000…1401298464324817``,
#: is 65 characters so) is a line of about 600 that makes a frame of 87 bytes. Four times
#: a frame takes any such line with room to space it, and a file's path. The console's and
#: the REPL's command lines take no more; a longer line (a paste, a ``run`` file) is
#: refused whole.
MAX_LINE = 1024


def check_length(line: str) -> None:
    """InputError for a line longer than :data:`MAX_LINE` (nothing of it is read)."""
    if len(line) > MAX_LINE:
        raise InputError(
            f"a command line is at most {MAX_LINE} characters: this one has {len(line):,}, "
            "and nothing of it was run"
        )
