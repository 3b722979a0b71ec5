"""A new target starts every watched row afresh: no value, change or trend of the
controller left behind is ever shown as the new one's."""

from __future__ import annotations

from pathlib import Path

import pytest

from rac_console.commands.language import VarRef
from rac_console.protocol import VT, Variant, kind_of
from tests.support.drivers import Front, make_app, results_text, type_line, until

I10 = VarRef(kind_of("I"), 10)


def test_a_row_shows_no_value_or_change_of_the_old_target(front: Front) -> None:
    front.run("put I 10 22")
    front.run("watch I 10")
    front.until(lambda: front.rows["I10"].variant == Variant(VT.I4, 22), "22 from the first")
    front.run("connect sim")  # a new simulator: I10 is 0 there
    front.until(
        lambda: front.rows["I10"].variant == Variant(VT.I4, 0) and front.rows["I10"].status == "OK",
        "the new target's value",
    )
    assert front.rows["I10"].changed_at is None  # 22 → 0 happened on neither controller


@pytest.mark.slow  # over half a second
async def test_the_trends_of_the_old_target_go(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 40)) as pilot:
        await type_line(pilot, "put I 10 22")
        await type_line(pilot, "watch I 10")
        await until(
            pilot, lambda: 22 in app.main_screen.members.trends.last(I10, 0, 16), "a trend of 22"
        )
        await type_line(pilot, "connect sim")
        await until(
            pilot, lambda: "connected to the built-in simulator" in results_text(app), "the new one"
        )
        await until(
            pilot,
            lambda: 0 in app.main_screen.members.trends.last(I10, 0, 16),
            "a sample of the new one",
        )
        assert 22 not in app.main_screen.members.trends.last(I10, 0, 16)


def test_a_csv_log_ends_at_the_change_of_target(front: Front, tmp_path: Path) -> None:
    path = tmp_path / "cell.csv"
    front.run("watch I 10")
    front.run(f"log {path}")
    front.until(lambda: front.status is not None and front.status.csv_log is not None, "logging")
    front.run("connect sim")
    front.until(lambda: any("CSV log stopped" in a for a in front.alerts), "the log's end said")
    assert front.status is not None and front.status.csv_log is None
