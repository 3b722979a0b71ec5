"""The rules of what a served session may send and cost (present/served_bounds.py) and
how a served console tells it ran out of memory (tui/memory_limit.py), alone: the
budgets on a clock of the test's, the texts, the limit read from the environment."""

from __future__ import annotations

from rac_console.present.served_bounds import (
    BYTES_PER_SECOND,
    MEMORY_ENV,
    MESSAGE_COST,
    MESSAGE_MOST,
    OUT_OF_MEMORY,
    Budget,
    SentBudget,
    ended_text,
    keys_dropped_text,
    sent_dropped_text,
)
from rac_console.tui.memory_limit import is_memory_error, limit_from


def test_a_budget_spends_its_burst_then_refills_at_its_rate_never_past_the_burst() -> None:
    budget = Budget(burst=10, rate=5, now=0.0)
    assert [budget.take(1, 0.0) for _ in range(11)] == [True] * 10 + [False]
    assert budget.take(5, 1.0) and not budget.take(1, 1.0)  # 5 a second
    assert not budget.take(11, 100.0)  # never more than the burst, however long it waited
    assert budget.take(10, 100.0)


def test_serve_takes_one_message_of_the_most_at_once_then_its_rate() -> None:
    sent = SentBudget(now=0.0)
    assert not sent.allows(MESSAGE_MOST + 1, 0.0)  # too big, whatever is left
    assert sent.allows(MESSAGE_MOST, 0.0)
    assert not sent.allows(1, 0.0)
    small = BYTES_PER_SECOND - MESSAGE_COST
    assert sent.allows(small, 1.0) and not sent.allows(small, 1.0)


def test_a_flood_of_one_key_messages_costs_more_than_its_bytes() -> None:
    sent = SentBudget(now=0.0)
    taken = sum(sent.allows(1, 0.0) for _ in range(10_000))
    assert taken == (MESSAGE_MOST + MESSAGE_COST) // (1 + MESSAGE_COST)


def test_what_the_console_and_the_page_are_told() -> None:
    assert keys_dropped_text(1).startswith("1 key was dropped: a served console takes 1024 keys")
    assert keys_dropped_text(31_626).startswith("31,626 keys were dropped")
    assert sent_dropped_text(70_000) == (
        "70,000 bytes the browser sent were dropped: a served console takes 64 KiB at once "
        "and 16 KiB a second (paste a longer text in parts)"
    )
    assert ended_text(0, 1024) is None  # it quit: the page says "Session ended." alone
    out = ended_text(OUT_OF_MEMORY, 1024)
    assert out == (
        "the console reached its memory limit of 1,024 MiB and ended "
        "(rac-console serve --session-memory)"
    )
    assert (
        ended_text(-9, 1024)
        == "the console was killed (status -9): the server's terminal may say why"
    )
    assert ended_text(1, None) == "the console ended (status 1): the server's terminal may say why"
    for status in (OUT_OF_MEMORY, -9, 1, None):
        said = ended_text(status, 1_000_000)
        assert said is not None and len(said.encode()) <= 123  # a close reason's most


class WorkerFailed(Exception):
    """As Textual's: the worker's own error in ``error``."""

    def __init__(self, error: BaseException) -> None:
        super().__init__(str(error))
        self.error = error


def test_a_memory_error_is_found_where_textual_wraps_or_chains_it() -> None:
    assert is_memory_error(MemoryError())
    assert is_memory_error(WorkerFailed(MemoryError()))
    try:
        try:
            raise MemoryError
        except MemoryError:
            raise SystemError("error return without exception set")  # noqa: B904
    except SystemError as chained:
        assert is_memory_error(chained)
    assert not is_memory_error(ValueError("no"))
    assert not is_memory_error(None)


def test_the_limit_is_read_from_the_sessions_environment() -> None:
    assert limit_from({MEMORY_ENV: str(1024 << 20)}) == 1024 << 20
    for text in ("", "0", "-5", "1e9", "١٢٣"):
        assert limit_from({MEMORY_ENV: text}) is None
    assert limit_from({}) is None
