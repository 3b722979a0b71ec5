"""The REPL's question before a write on a ``confirm`` target: ``Write I10: 14 → 15 on
Cell 3? [y/N]``; only y or yes writes.

Keys typed ahead before the question are dropped, not taken as its answer, and a yes
within :data:`CONFIRM_GUARD_SECONDS` of it is asked again; Ctrl-C or Ctrl-D is a No.
(Without a terminal, ``run`` refuses such a write.)
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from prompt_toolkit import PromptSession
from prompt_toolkit.input.typeahead import clear_typeahead

from ..engine import CONFIRM_GUARD_SECONDS, ConfirmWrite
from ..present.render import notice_text
from .prompt_parts import confirm_message


async def ask_write(
    prompt: PromptSession[Any],
    question: ConfirmWrite,
    target: str | None,
    say: Callable[..., None],
) -> bool:
    """Ask ``question`` at ``prompt`` until it is answered with care: True for a yes."""
    try:
        while True:
            clear_typeahead(prompt.input)
            asked_at = time.monotonic()
            answer = await prompt.prompt_async(confirm_message(question, target))
            yes = answer.strip().lower() in ("y", "yes")
            if not yes or time.monotonic() - asked_at >= CONFIRM_GUARD_SECONDS:
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
