"""The command each served session runs, and how a session knows it is served.

Every WebSocket starts one console process. Its command is a list of arguments run
without a shell, so nothing from the command line (a profile's name, a host) is ever
read by a shell: ``[python, -P, -m, rac_console, --host=NAME, ..., --read-only]``. Options
and their values go as one word each (``--host=NAME``), so a value that starts with
``-`` stays a value.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from ..engine.setup.poll_bounds import SERVED_MAX_ROWS, SERVED_MIN_INTERVAL, served_environment
from ..present.served import SERVED_ENV as SERVED_ENV
from ..present.served import WEB_DRIVER as WEB_DRIVER
from ..present.served import served as served
from ..present.served_bounds import DEFAULT_MEMORY_MIB, MEMORY_ENV


def session_argv(
    target_words: Sequence[str], allow_writes: bool, python: str | None = None
) -> tuple[str, ...]:
    """The console's command for one session: the target options as given to ``serve``,
    and ``--read-only`` unless writes are allowed."""
    for word in target_words:
        if not word.startswith("--") or ("=" not in word and word != "--no-verify"):
            raise ValueError(f"a target option is one --name=value word: {word!r}")
    read_only = () if allow_writes else ("--read-only",)
    # -P: the installed console, never a rac_console folder where serve was started.
    return (python or sys.executable, "-P", "-m", "rac_console", *target_words, *read_only)


def session_environment(
    min_interval: float = SERVED_MIN_INTERVAL,
    max_rows: int = SERVED_MAX_ROWS,
    memory_mib: int = DEFAULT_MEMORY_MIB,
) -> dict[str, str]:
    """What a session's environment adds to the server's (textual-serve adds the
    driver, the size and the colours): that it is served, its poll bounds, and its
    memory limit (none for 0)."""
    memory = {MEMORY_ENV: str(memory_mib << 20)} if memory_mib else {}
    return {SERVED_ENV: "1", **served_environment(min_interval, max_rows), **memory}
