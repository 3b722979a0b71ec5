"""Defects found in review, each pinned by the behaviour a user would see."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path

import pytest
from session_helpers import AsyncSession
from tui_helpers import make_app, results_text, type_line, until

from rac_console.engine.watchlist import load
from rac_console.present.history import History
from rac_console.protocol import (
    InputError,
    ProtocolError,
    Variant,
    format_variant,
    kind_of,
    parse_variant,
)
from rac_console.protocol.hresult import E_INVALIDARG
from rac_console.protocol.variant import canonical_r4
from rac_console.session import Frame
from rac_console.sim.controller import SimulatedController
from rac_console.tui.watch_table import WatchTable


async def _slow_echo_server(delay: float) -> tuple[asyncio.Server, int]:
    async def serve(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            while line := await reader.readuntil(b"\r"):
                index = line.split(b":")[2]
                await asyncio.sleep(delay)
                writer.write(b"0,3," + index + b"\r")
        except (asyncio.IncompleteReadError, ConnectionError):
            pass

    server = await asyncio.start_server(serve, "127.0.0.1", 0)
    return server, server.sockets[0].getsockname()[1]


def test_a_cancelled_request_never_leaves_its_reply_for_the_next() -> None:
    async def scenario() -> int:
        server, port = await _slow_echo_server(0.2)
        async with server, AsyncSession("127.0.0.1", port, timeout=2) as session:
            with pytest.raises(TimeoutError):
                # The await is given up; the GET itself still runs on the session's
                # thread and takes its own reply, so the next request waits for it.
                await asyncio.wait_for(session.get(kind_of("I"), 1), 0.05)
            reply = await session.get(kind_of("I"), 2)
            return reply.response.variant.value

    assert asyncio.run(scenario()) == 2


def test_a_failing_frame_observer_does_not_break_the_session() -> None:
    from rac_console.sim.server import SimulatorServer

    async def scenario() -> list[int]:
        async with SimulatorServer() as sim, AsyncSession(sim.host, sim.port) as session:

            def broken(frame: Frame) -> None:
                raise OSError(28, "No space left on device")

            session.add_frame_observer(broken)
            await session.put(kind_of("I"), 1, Variant(3, 11))
            await session.put(kind_of("I"), 2, Variant(3, 22))
            first = await session.get(kind_of("I"), 1)
            second = await session.get(kind_of("I"), 2)
            return [first.response.variant.value, second.response.variant.value]

    assert asyncio.run(scenario()) == [11, 22]


def test_zero_keeps_its_sign_and_r4_text_is_shortest() -> None:
    import math

    minus_zero = parse_variant("4,-0")
    assert minus_zero.vt == 4
    assert minus_zero.value == 0.0 and math.copysign(1.0, minus_zero.value) == -1.0
    assert format_variant(minus_zero) == "4,-0"
    plus_zero = parse_variant("4,0")
    assert plus_zero.value == 0.0 and math.copysign(1.0, plus_zero.value) == 1.0
    assert format_variant(Variant(4, 0.0)) == "4,0"
    assert format_variant(Variant(8196, [0.0, 0.0])) == "8196,0,0"
    assert format_variant(Variant(4, canonical_r4(2.0**-96))) == "4,1.2621775e-29"


def test_huge_numbers_and_deep_nesting_are_protocol_errors() -> None:
    for text in ("3," + "9" * 5000, "9" * 5000 + ",1", "12," + "(12," * 5000 + "(3,1)"):
        with pytest.raises(ProtocolError):
            parse_variant(text)
    with pytest.raises(InputError):
        kind_of("I").value_from_text("9" * 5000)


def test_cli_refuses_a_huge_index_without_a_traceback() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", "get", "I", "9" * 5000],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr and "index" in result.stderr


def test_control_characters_from_the_controller_are_escaped_on_screen() -> None:
    from rac_console.commands.language import VarRef
    from rac_console.present.render import value_text

    shown = value_text(VarRef(kind_of("S"), 5), Variant(8, "A\x1b]0;x\x07B")).plain
    assert "\x1b" not in shown and "\\x1b" in shown


def test_simulator_refuses_strings_it_could_not_send_back() -> None:
    controller = SimulatedController()
    reply, _ = controller.handle(b"PUT:RC8:5:S:8,a\nb")
    assert reply == f"{E_INVALIDARG - 2**32}\r".encode()
    assert controller.handle(b"GET:RC8:5:S:")[0] == b"0,8,\r"


@pytest.mark.parametrize("content", ["watch = 5", "\xff\xfe", "[watch]\ntype = 'P'\n"])
def test_bad_watch_list_files_give_a_message(tmp_path: Path, content: str) -> None:
    path = tmp_path / "cell.toml"
    path.write_bytes(content.encode("latin-1"))
    if "index" not in content and "type" in content:
        with pytest.raises(InputError, match="no 'index'"):
            load(path)
    else:
        with pytest.raises(InputError):
            load(path)


def test_record_file_that_cannot_be_opened_is_a_clear_error(tmp_path: Path) -> None:
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "rac_console",
            "--record",
            str(tmp_path / "no" / "x.jsonl"),
            "get",
            "I",
            "1",
        ],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 2
    assert "cannot write the record file" in result.stderr and "Traceback" not in result.stderr


def test_history_rewrite_ignores_a_stale_temporary_file(tmp_path: Path) -> None:
    path = tmp_path / "history"
    (tmp_path / "history.tmp").write_text("stale1\nstale2\n")
    history = History(path, limit=2)
    for n in range(6):
        history.append(f"cmd{n}")
    assert path.read_text().splitlines()[-2:] == ["cmd4", "cmd5"]
    assert "stale1" not in path.read_text()


async def test_a_label_is_shown_as_typed_never_as_markup(tmp_path: Path) -> None:
    app = make_app(tmp_path)
    async with app.run_test(size=(120, 30)) as pilot:
        await type_line(pilot, "watch I 1 [/x] [red]tool")
        table = app.query_one(WatchTable)
        await until(pilot, lambda: table.row_count == 1, "the row")
        assert table.get_cell("I1", "label").plain == "[/x] [red]tool"
        assert app.is_running and "watching I1" in results_text(app)
