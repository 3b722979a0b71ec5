"""The REPL's question before a write on a ``confirm`` target: ``Write I10: 14 → 15 on
Cell 3? [y/N]``; only y or yes writes.

Keys typed ahead before the question are dropped, not taken as its answer, and a yes
within :data:`CONFIRM_GUARD_SECONDS` of it is asked again; Ctrl-C or Ctrl-D is a No.
The question ends in ``…`` during that time and in ``[y/N]`` once a yes counts, so
whoever answers sees when. (Without a terminal, ``run`` refuses such a write.)
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Any

from prompt_toolkit import PromptSession
from prompt_toolkit.input.typeahead import clear_typeahead

from ..engine import CONFIRM_GUARD_SECONDS, ConfirmWrite
from ..present.render import notice_text
from .prompt_parts import confirm_message

#: How often the question looks whether a yes counts yet (to say ``[y/N]``).
READY_TICK = 0.05


async def ask_write(
    prompt: PromptSession[Any],
    question: ConfirmWrite,
    target: str | None,
    say: Callable[..., None],
) -> bool:
    """Ask ``question`` at ``prompt`` until it is answered with care: True for a yes."""
    try:
        while True:
            yes, in_time = await _ask_once(prompt, question, target)
            if not yes or in_time:
                return yes
            say(
                notice_text(
                    f"answered within {CONFIRM_GUARD_SECONDS:g} s of the question, as keys "
                    "typed ahead would be: answer again",
                    error=True,
                )
            )
    except (KeyboardInterrupt, EOFError):
        return False


async def _ask_once(
    prompt: PromptSession[Any], question: ConfirmWrite, target: str | None
) -> tuple[bool, bool]:
    """The question asked once: whether the answer is a yes, and whether it came after
    the guard time (when the question said ``[y/N]``)."""
    clear_typeahead(prompt.input)
    asked_at = time.monotonic()

    def ready() -> bool:
        return time.monotonic() - asked_at >= CONFIRM_GUARD_SECONDS

    async def redraw_when_ready() -> None:
        while not ready():
            await asyncio.sleep(READY_TICK)
        prompt.app.invalidate()  # drawn again: ``…`` becomes ``[y/N]``

    redraw = asyncio.ensure_future(redraw_when_ready())
    try:
        answer = await prompt.prompt_async(lambda: confirm_message(question, target, ready()))
    finally:
        redraw.cancel()
    return answer.strip().lower() in ("y", "yes"), ready()
