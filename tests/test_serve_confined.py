"""A console served to a browser reaches its controller and nothing else of the machine
serving it: no file written or read (``save``, ``load``, ``log``, ``record``,
``transcript``), no connection opened elsewhere (``connect``, ``publish``). Judged from
the machine's side: the files that are not there, the listeners no one reached."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from rac_console.commands.routing import Reach
from rac_console.engine.commands.builtin import BUILTIN
from rac_console.engine.setup.where import AT_A_TERMINAL, Where
from tests.support.servers import RecordingServer
from tests.support.serving import Console, Served, consoles_of, spend_link, start_serve, until

pytest.importorskip("textual_serve", reason="needs the extra web")


def open_session(served: Served) -> Console:
    """The link spent as a browser would, and the session's socket opened."""
    login = spend_link(served)
    headers = {
        "Host": served.host,
        "Origin": served.origin,
        "Cookie": f"{served.cookie_name}={login.cookie}",
    }
    console = Console(served.port, login.socket + "?width=120&height=40", headers)
    assert console.status == 101, console.made.answer
    console.send("resize", {"width": 120, "height": 40})  # as the page does once open
    return console


@pytest.mark.slow
def test_a_served_session_writes_no_file_and_reaches_no_other_host(
    env, running, tmp_path: Path
) -> None:
    files = tmp_path / "files"
    files.mkdir()
    kept = files / "kept.toml"
    kept.write_text('[[watch]]\nvar = "I 77"\n', encoding="utf-8")
    other_controller = RecordingServer(lambda line: b"0,3,1")
    broker = socket.create_server(("127.0.0.1", 0))
    broker.setblocking(False)  # read once the console has ended (below)
    broker_port = broker.getsockname()[1]
    try:
        served = start_serve(env, running, "--allow-writes")
        console = open_session(served)
        console.until("SERVED", "connected")
        lines = {
            "save": f"save {files / 'bashrc'}",
            "load": f"load {kept}",
            "log": f"log {files / 'log.csv'}",
            "record": f"record {files / 'frames.txt'}",
            "transcript": f"transcript {files / 'transcript.txt'}",
            "connect": f"connect 127.0.0.1:{other_controller.port}",
            "publish": f"publish mqtt://127.0.0.1:{broker_port}/line2",
        }
        for word, line in lines.items():
            console.type_line(line)
            console.until(f"'{word}' is not for a served console")
        console.type_line("get I 1")
        console.until("I1 = 1")  # the session still works, on its own target
        # A screenshot goes to the browser, not into the serving machine's Downloads.
        (Path(env["HOME"]) / "Downloads").mkdir()
        console.send("stdin", "\x10")  # Ctrl+P: the palette
        console.until("Search for commands")
        console.send("stdin", "screenshot")
        console.until("Save an SVG")
        console.send("stdin", "\r")
        console.until_message(lambda m: isinstance(m, list) and m[0] == "deliver_file_start")
        console.close()
        # Watched for the session's whole life: once its console has ended, a connection
        # it ever made would be in the broker's accept queue (the kernel completes it
        # without an accept) and in the recording controller's peers.
        until(lambda: consoles_of(served.running.process.pid) == [], "the console ending")
        assert list((Path(env["HOME"]) / "Downloads").iterdir()) == []
        assert sorted(p.name for p in files.iterdir()) == ["kept.toml"]
        assert other_controller.peers == []
        with pytest.raises(BlockingIOError):
            broker.accept()
    finally:
        other_controller.close()
        broker.close()


READS_OR_WRITES_FILES = {"save", "load", "log", "record", "transcript"}
OPENS_CONNECTIONS = {"connect", "publish"}


def test_what_a_command_reaches_is_declared_on_its_spec() -> None:
    reach = {spec.name: spec.traits.reaches for spec in BUILTIN}
    assert {n for n, r in reach.items() if r is Reach.FILES} == READS_OR_WRITES_FILES
    assert {n for n, r in reach.items() if r is Reach.NETWORK} == OPENS_CONNECTIONS
    served = set(BUILTIN.runs_in(Where.SERVED))
    assert not served & (READS_OR_WRITES_FILES | OPENS_CONNECTIONS)
    # Everything else the console runs, a served console runs too.
    console = set(BUILTIN.runs_in(Where.CONSOLE))
    assert console - served == READS_OR_WRITES_FILES | OPENS_CONNECTIONS
    assert Where.SERVED in AT_A_TERMINAL


@pytest.mark.slow
def test_a_served_session_neither_reads_nor_writes_the_machines_history_or_settings(
    env, running, config
) -> None:
    """The operator's history (Up, grey suggestions) and settings stay the operator's:
    a session in a browser does not see them, and leaves both files as they were; its
    palette names no profile of the config file."""
    from rac_console.present.history import default_history_path

    history = default_history_path()
    history.parent.mkdir(parents=True)
    history.write_text("connect plc-line3\nsave /home/op/secret-watch.toml\n", encoding="utf-8")
    settings = config('[target.line3]\nhost = "10.0.0.5"\nlabel = "line 3 welder"\n')
    kept_history, kept_settings = history.read_bytes(), settings.read_bytes()
    served = start_serve(env, running)
    console = open_session(served)
    console.until("SERVED", "connected")
    console.send("stdin", "\x1b[A")  # Up: the newest line of the history, if any
    console.type_line("get I 1")  # Up recalled nothing: this line is the whole line
    console.until("I1 = 1")
    shown = console.until("› get I 1")
    assert "secret-watch" not in shown
    console.send("stdin", "\x1b[15~")  # F5: the I/O grid (a setting)
    console.until("I/O")
    console.send("stdin", "connect ")
    console.send("stdin", "\t")  # completion: what connect could take
    # One candidate is put on the line; several are listed.
    shown = console.until_any("the built-in simulator", "connect sim")
    assert "line3" not in shown and "welder" not in shown
    console.send("stdin", "\x15")  # Ctrl+U: the line emptied
    console.send("stdin", "\x10")  # Ctrl+P: the palette
    console.until("Search for commands")
    console.send("stdin", "connect")
    shown = console.until("connect")
    assert "line3" not in shown and "welder" not in shown
    console.close()  # the server ends the session's console
    until(lambda: consoles_of(served.running.process.pid) == [], "the console ending")
    assert history.read_bytes() == kept_history
    assert settings.read_bytes() == kept_settings
