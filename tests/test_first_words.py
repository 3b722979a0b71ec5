"""The first thing a newcomer reads at the command line is a read: the placeholder
suggests a write (``put IO 20 on``) on the built-in simulator only, never on a live
controller, a read-only one or a cell's."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from rac_console.sim.thread import SimulatorThread
from tests.support.drivers import make_app, until


@pytest.fixture
def controller() -> Iterator[SimulatorThread]:
    """A simulator at an address: to the console, a live controller."""
    with SimulatorThread() as simulator:
        yield simulator


async def placeholder_once_connected(app, size=(100, 30)) -> str:
    async with app.run_test(size=size) as pilot:
        # The placeholder follows a status as it arrives, before the status line is drawn.
        await until(
            pilot, lambda: "connected" in app.main_screen.panes.status_bar.line.plain, "connected"
        )
        return str(app.main_screen.panes.command_line.placeholder)


async def test_on_a_live_controller_the_placeholder_suggests_no_write(
    tmp_path: Path, controller: SimulatorThread
) -> None:
    app = make_app(tmp_path, controller.host, controller.port)
    shown = await placeholder_once_connected(app)
    assert "get P 1" in shown and "put" not in shown


@pytest.mark.slow  # over half a second
async def test_on_a_read_only_target_the_placeholder_suggests_no_write(tmp_path: Path) -> None:
    app = make_app(tmp_path, read_only=True)
    shown = await placeholder_once_connected(app)
    assert "get P 1" in shown and "put" not in shown


async def test_on_the_built_in_simulator_a_write_is_suggested(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    shown = await placeholder_once_connected(app)
    assert "put IO 20 on" in shown


async def test_the_repls_help_speaks_of_the_repl_and_leaving_is_suggested(
    tmp_path: Path,
) -> None:
    from tests.support.drivers import Driver

    driver = Driver(tmp_path)

    async def steps(d: Driver) -> None:
        d.type("help\r")
        await d.until(lambda out: "raw RAC entry" in out, "the help")
        d.type("exit\r")
        await d.until(lambda out: "did you mean quit?" in out, "the suggestion")
        d.type("q\r")
        await d.until(lambda out: out.count("did you mean quit?") == 2, "again for q")

    out = await driver.run(steps)
    assert "live table" not in out and "leave the console" not in out
