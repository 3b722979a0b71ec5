"""A served console's memory, bounded: the limit ``rac-console serve`` gives each
session (:data:`~..present.served_bounds.MEMORY_ENV`) is set on the process for the OS
to enforce, and the console ends at it with
:data:`~..present.served_bounds.OUT_OF_MEMORY`, which serve tells the page.

At the limit an allocation fails wherever it happens to be: a MemoryError in a handler
or a thread, or a C extension that returns an error without one (SystemError was seen),
and a console whose failure was caught in the wrong place hung at its limit, deaf. So
the console does not wait for one to surface: a watchdog thread reads the process's size
every :data:`WATCH_SECONDS` and ends it once it passes :data:`WATCH_SHARE` of its limit,
and the app ends it at the first MemoryError it sees. ``os._exit``: nothing is allocated
on the way out, and nothing is printed.

The OS's limit: on Linux ``RLIMIT_DATA``, what the process writes to (its heap, its
private mappings, its threads' stacks), the size the watchdog reads too (``/proc/self/
statm``); on other POSIX systems ``RLIMIT_AS`` (macOS accepts it and does not enforce
it: the watchdog, reading the peak resident size, does). Windows has no such limit
here, and ``serve`` does not run there (its extra is not installed on Windows).
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Mapping
from typing import NoReturn

from ..present.served_bounds import MEMORY_ENV, OUT_OF_MEMORY

#: How often the watchdog reads the process's size, and at what share of the limit it
#: ends the console (the rest is for the allocations between two reads).
WATCH_SECONDS = 0.25
WATCH_SHARE = 0.9


def limit_from(environ: Mapping[str, str]) -> int | None:
    """The limit serve set, in bytes; None when there is none (or it cannot be read)."""
    text = environ.get(MEMORY_ENV, "")
    if not (text.isascii() and text.isdigit()):
        return None
    limit = int(text)
    return limit if limit > 0 else None


def out_of_memory() -> NoReturn:
    """End the console at once, with the status serve reads as "out of memory"."""
    os._exit(OUT_OF_MEMORY)


def is_memory_error(error: BaseException | None) -> bool:
    """Whether ``error``, or one it came from (a worker's failure wraps it), is a
    MemoryError."""
    for _ in range(16):  # a chain, never a loop
        if error is None:
            return False
        if isinstance(error, MemoryError):
            return True
        wrapped = getattr(error, "error", None)  # textual.worker.WorkerFailed
        error = (
            wrapped
            if isinstance(wrapped, BaseException)
            else (error.__cause__ or error.__context__)
        )
    return False


def _set_os_limit(limit: int) -> bool:
    """The OS's limit on this process (see the module's doc); False where there is none."""
    try:
        import resource
    except ImportError:  # Windows
        return False
    kind = resource.RLIMIT_DATA if sys.platform.startswith("linux") else resource.RLIMIT_AS
    _soft, hard = resource.getrlimit(kind)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    try:
        resource.setrlimit(kind, (limit, limit))
    except (OSError, ValueError):
        return False
    return True


def _size() -> int | None:
    """This process's size as its limit counts it, in bytes (None: cannot tell)."""
    if sys.platform.startswith("linux"):
        with open("/proc/self/statm", "rb") as statm:
            fields = statm.read().split()
        return int(fields[5]) * os.sysconf("SC_PAGE_SIZE")  # data and stack
    try:
        import resource
    except ImportError:
        return None
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak if sys.platform == "darwin" else peak * 1024


def _watch(most: float) -> None:
    try:
        while True:
            size = _size()
            if size is None:
                return
            if size >= most:
                out_of_memory()
            time.sleep(WATCH_SECONDS)
    except MemoryError:  # even reading the size failed: at the limit
        out_of_memory()


def bound_memory(environ: Mapping[str, str] | None = None) -> int | None:
    """Set the limit serve gave this console, and start its watchdog; the limit, or
    None when there is none."""
    limit = limit_from(os.environ if environ is None else environ)
    if limit is None:
        return None
    _set_os_limit(limit)
    watchdog = threading.Thread(
        target=_watch, args=(limit * WATCH_SHARE,), name="memory-watchdog", daemon=True
    )
    watchdog.start()
    return limit
