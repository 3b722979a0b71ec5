"""What the REPL asks of the terminal: keys typed ahead held unseen while a line runs,
and no mouse input."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator

from prompt_toolkit.input import Input
from prompt_toolkit.key_binding import KeyBindings, KeyPressEvent
from prompt_toolkit.keys import Keys

if sys.platform != "win32":
    import termios


def no_mouse() -> KeyBindings:
    """The REPL takes no mouse input. A cut-short mouse report (a paste, a terminal
    that sends one anyway) made prompt-toolkit's own handler fail with a traceback
    and stop reading: these events are dropped instead."""
    bindings = KeyBindings()

    @bindings.add(Keys.Vt100MouseEvent)
    @bindings.add(Keys.WindowsMouseEvent)
    def _(event: KeyPressEvent) -> None:
        return None

    return bindings


@contextlib.contextmanager
def keys_held(keys: Input) -> Iterator[None]:
    """While a typed line runs, the keys typed ahead wait unseen for the next prompt.

    Between two prompts the terminal was back in its cooked mode: it echoed the keys
    typed ahead at the cursor, where the result was about to be printed (``get I 2I1 =
    1``). Here echo and line editing are off, so the terminal holds every key (a
    half-typed line too) until the next prompt reads it and shows it after the result;
    signals stay on, so Ctrl-C still cancels the command. Nothing on a pipe, a file or
    Windows, where no terminal echoes."""
    fd = _terminal_fd(keys)
    if fd is None or sys.platform == "win32":
        yield
        return
    before = termios.tcgetattr(fd)
    held = termios.tcgetattr(fd)
    held[3] &= ~(termios.ECHO | termios.ICANON)
    held[6][termios.VMIN], held[6][termios.VTIME] = 1, 0
    termios.tcsetattr(fd, termios.TCSANOW, held)  # TCSANOW: the keys typed stay
    try:
        yield
    finally:
        with contextlib.suppress(termios.error):
            termios.tcsetattr(fd, termios.TCSANOW, before)


def _terminal_fd(keys: Input) -> int | None:
    try:
        fd = keys.fileno()
    except (NotImplementedError, OSError, ValueError):
        return None
    return fd if os.isatty(fd) else None
