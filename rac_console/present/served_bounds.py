"""What one served session may send and cost, and what the browser is told when it
goes past: the rules alone (``rac-console serve``'s socket and the served console's
driver apply them; nothing here reads a clock or a socket).

A browser sends what is typed as ``["stdin", TEXT]`` messages: one key each as a person
types, a whole paste in one. Keys are the costly kind: each is an event the console
handles on its own, and 32 KiB of them sent at once took a console to 705 MB and two
minutes of a core. So:

- serve drops a ``stdin`` message past :data:`MESSAGE_MOST` bytes, or past a budget of
  :data:`BYTES_PER_SECOND` (a burst of :data:`MESSAGE_MOST`), and tells the console, which
  says so in its results (:func:`sent_dropped_text`);
- the console's driver drops keys past a budget of :data:`KEYS_PER_SECOND` (a burst of
  :data:`KEYS_AT_ONCE`) and says so (:func:`keys_dropped_text`): a paste is one event
  and goes whole;
- the session's console runs under a memory limit the OS enforces
  (:data:`MEMORY_ENV`); at it, the console ends with :data:`OUT_OF_MEMORY` and serve
  tells the page why (:func:`ended_text`).
"""

from __future__ import annotations

from ..commands.line import MAX_LINE

#: The most bytes one ``stdin`` message may hold (a paste of about 2,000 lines).
MESSAGE_MOST = 64 * 1024
#: What a session may send as ``stdin`` each second, once a burst of MESSAGE_MOST is spent.
BYTES_PER_SECOND = 16 * 1024
#: What each message costs besides its bytes: a flood of one-key messages is bounded too
#: (a person's keys and a mouse's moves come to a few hundred a second at most).
MESSAGE_COST = 32
#: The keys a served console takes at once, and each second after that: a whole command
#: line at once (a barcode reader or a tool that types one in), and far more each second
#: than anyone types (a held key repeats about 30 times a second).
KEYS_AT_ONCE = MAX_LINE
KEYS_PER_SECOND = 256

#: The meta message serve sends a session's console for input it dropped (its ``bytes``).
DROPPED_META = "rac-console-dropped"

#: Set in a served session's environment: the most memory its console may take, in
#: bytes (absent: no limit).
MEMORY_ENV = "RAC_CONSOLE_MEMORY"
#: What each session may take unless ``serve --session-memory`` says otherwise, in MiB:
#: a served console's data is about 85 MB at start and 156 MB after 13 minutes of 256
#: rows of T (serve's default cap); a row's trend keeps up to 0.9 MB (docs/cli.md).
DEFAULT_MEMORY_MIB = 1024
#: The least limit ``serve`` takes, in MiB (0 aside: no limit).
LEAST_MEMORY_MIB = 128
#: The exit status of a served console that ran out of memory (ENOMEM's number).
OUT_OF_MEMORY = 12


class Budget:
    """A token bucket: ``burst`` at once, refilled at ``rate`` a second, never above
    ``burst``; the clock is the caller's."""

    def __init__(self, burst: float, rate: float, now: float) -> None:
        self.burst = burst
        self.rate = rate
        self._left = burst
        self._at = now

    def take(self, amount: float, now: float) -> bool:
        """Spend ``amount`` if that much is left at ``now``; False (nothing spent) if not."""
        self._left = min(self.burst, self._left + max(0.0, now - self._at) * self.rate)
        self._at = now
        if amount > self._left:
            return False
        self._left -= amount
        return True


class SentBudget:
    """serve's bound on one session's ``stdin`` messages: at most :data:`MESSAGE_MOST`
    bytes each, and :data:`BYTES_PER_SECOND` once a burst of one such message is spent
    (each message costing :data:`MESSAGE_COST` more than its bytes)."""

    def __init__(self, now: float) -> None:
        self._budget = Budget(MESSAGE_MOST + MESSAGE_COST, BYTES_PER_SECOND, now)

    def allows(self, size: int, now: float) -> bool:
        """Whether a message of ``size`` bytes goes to the console (it is then spent)."""
        return size <= MESSAGE_MOST and self._budget.take(size + MESSAGE_COST, now)


def keys_dropped_text(count: int) -> str:
    """What the console says of keys dropped by its driver."""
    keys = "1 key was" if count == 1 else f"{count:,} keys were"
    return (
        f"{keys} dropped: a served console takes {KEYS_AT_ONCE} keys at once and "
        f"{KEYS_PER_SECOND} a second (a paste goes whole)"
    )


def sent_dropped_text(size: int) -> str:
    """What the console says of input serve dropped (``size`` bytes of it)."""
    return (
        f"{size:,} bytes the browser sent were dropped: a served console takes "
        f"{MESSAGE_MOST // 1024} KiB at once and {BYTES_PER_SECOND // 1024} KiB a second "
        "(paste a longer text in parts)"
    )


def ended_text(status: int | None, memory_mib: int | None) -> str | None:
    """Why a session's console ended without being asked to, for the page (at most 123
    bytes: a WebSocket's close reason); None for an end it asked for (status 0)."""
    if status == OUT_OF_MEMORY:
        limit = f" of {memory_mib:,} MiB" if memory_mib else ""
        return (
            f"the console reached its memory limit{limit} and ended "
            "(rac-console serve --session-memory)"
        )
    if status == 0:
        return None
    how = "was killed" if status is not None and status < 0 else "ended"
    code = f" (status {status})" if status is not None else ""
    return f"the console {how}{code}: the server's terminal may say why"
