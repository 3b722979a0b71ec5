"""The console ends when its terminal goes away (a closed pty, a killed tmux session).

Textual's input thread reads an empty string from a hung-up terminal, takes it for piped
input and reads again: the console spun at two thirds of a CPU with nobody to see it.
Without a controlling terminal no SIGHUP comes, so a thread waits for the hang-up itself
(``poll`` with no events asked reports only POLLHUP and POLLERR: it costs nothing
meanwhile and takes no input from Textual's reader).
"""

from __future__ import annotations

import os
import select
import threading
from collections.abc import Callable
from contextlib import suppress

#: Once the terminal is gone the console has this long to close (the engine stopped, the
#: history written) before the process ends anyway: a screen write may block for ever
#: with nobody reading.
CLOSE_WAIT = 5.0
#: The exit status of a console whose terminal went away, as a shell shows a SIGHUP's.
HANGUP_STATUS = 129


class TerminalWatch:
    """Calls ``gone`` (from its own thread) once ``fd``'s terminal hangs up, and ends the
    process CLOSE_WAIT later unless :meth:`stop` came first."""

    def __init__(self, fd: int, gone: Callable[[], None]) -> None:
        self._fd = fd
        self._gone = gone
        self._wake_read, self._wake_write = os.pipe()
        self._stopped = threading.Event()
        self._signalled = False  # a SIGHUP said the terminal went
        self._thread = threading.Thread(target=self._run, name="rac-terminal-watch", daemon=True)

    def start(self) -> TerminalWatch:
        self._thread.start()
        return self

    def hung_up(self) -> None:
        """A SIGHUP came: the terminal went, as if the thread had seen it."""
        self._signalled = True
        self._wake()

    def _wake(self) -> None:
        with suppress(OSError):  # the thread may have ended already
            os.write(self._wake_write, b"x")

    def stop(self) -> None:
        """The console closed: the thread ends, and ends nothing."""
        if self._stopped.is_set():
            return
        self._stopped.set()
        self._wake()
        self._thread.join(1.0)
        os.close(self._wake_write)

    def _run(self) -> None:
        poller = select.poll()
        poller.register(self._fd, 0)  # POLLHUP, POLLERR and POLLNVAL come anyway
        poller.register(self._wake_read, select.POLLIN)
        try:
            while not self._stopped.is_set():
                if any(fd == self._fd for fd, _ in poller.poll()) or self._signalled:
                    break
            else:
                return
            quiet_output()
            self._gone()
            if not self._stopped.wait(CLOSE_WAIT):
                os._exit(HANGUP_STATUS)
        finally:
            os.close(self._wake_read)


def quiet_output() -> None:
    """Point stdout and stderr at the null device: writes to a hung-up terminal fail,
    and Textual's writer thread dies at the first one, leaving the app to block on its
    full queue."""
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in (1, 2):
            os.dup2(null, fd)
    finally:
        os.close(null)
