"""``rac-console serve`` without a browser: each refusal with the status the README gives
(403 without the token or the cookie, 421 for a foreign Host, 403 for a foreign or
missing Origin on the socket, 404 for a folder of /static/, one session more taking the
slot of the oldest), the token bought once for a cookie, the headers; the guard's pure
decisions; the command a session runs; and the parts of textual-serve that are relied
on."""

from __future__ import annotations

import importlib.metadata
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

from rac_console.serve import guard as guard_module
from rac_console.serve.command import SERVED_ENV, WEB_DRIVER, served, session_argv
from rac_console.serve.guard import Guard, Login, Refusal, Slots, split_host
from rac_console.serve.page import INLINE_HANDLER, TAKEN_CODE, TAKEN_REASON
from tests.support.drivers import cli, one_error_line, profile
from tests.support.serving import (
    Console,
    Handshake,
    Served,
    consoles_of,
    cookie_of,
    handshake,
    request,
    spend_link,
    start_serve,
    until,
)

textual_serve = pytest.importorskip("textual_serve", reason="needs the extra web")


def with_cookie(served: Served, cookie: str, **more: str) -> dict[str, str]:
    return {"Host": served.host, "Cookie": f"{served.cookie_name}={cookie}", **more}


# ----------------------------------------------------------------- the server, over HTTP


@pytest.mark.slow
def test_the_token_buys_a_cookie_once_and_every_page_needs_it(env, running) -> None:
    served = start_serve(env, running)
    assert served.url.startswith(f"http://127.0.0.1:{served.port}/?token=")
    assert len(served.token) >= 40  # 32 random bytes

    nothing = request(served.port, "/", {"Host": served.host})
    assert nothing.status == 403
    assert "open the link" in nothing.text
    assert nothing.header("referrer-policy") == "no-referrer"
    wrong = request(served.port, "/?token=" + "x" * 43, {"Host": served.host})
    assert wrong.status == 403
    assert cookie_of_none(wrong, served.cookie_name)

    bought = request(served.port, f"/?token={served.token}", {"Host": served.host})
    assert bought.status == 303
    location = bought.header("location") or ""
    assert location.startswith("/#key=")  # the token leaves the address bar
    assert bought.header("referrer-policy") == "no-referrer"
    cookie, attributes = cookie_of(bought, served.cookie_name)
    assert cookie and cookie != served.token
    assert "httponly" in attributes and "samesite=strict" in attributes and "path=/" in attributes

    spent = request(served.port, f"/?token={served.token}", {"Host": served.host})
    assert spent.status == 403  # a link opens once
    again = request(served.port, f"/?token={served.token}", with_cookie(served, cookie))
    assert again.status == 303  # the browser that holds the cookie just goes on

    index = request(served.port, "/", with_cookie(served, cookie))
    assert index.status == 200
    assert f'data-session-websocket-url="ws://{served.host}/ws"' in index.text
    assert index.header("referrer-policy") == "no-referrer"
    assert "frame-ancestors 'none'" in (index.header("content-security-policy") or "")
    assert index.header("x-frame-options") == "DENY"
    wrong_cookie = request(served.port, "/", with_cookie(served, "x" * 43))
    assert wrong_cookie.status == 403
    assert request(served.port, "/static/js/textual.js", {"Host": served.host}).status == 403


def cookie_of_none(answer, name: str) -> bool:
    return not any(k == "set-cookie" and v.startswith(name) for k, v in answer.headers)


@pytest.mark.slow
def test_a_foreign_host_is_misdirected(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    cookie = login.cookie
    other_port = served.port + 1 if served.port < 65535 else served.port - 1
    for host in (
        f"evil.example:{served.port}",  # a name rebound to this machine (DNS rebinding)
        f"127.0.0.1.evil.example:{served.port}",
        f"127.0.0.1:{other_port}",
        "127.0.0.1",
        "",
    ):
        answer = request(served.port, "/", with_cookie(served, cookie, Host=host))
        assert answer.status == 421, host
        assert answer.header("referrer-policy") == "no-referrer"
    no_host = request(served.port, "/", {"Cookie": f"{served.cookie_name}={cookie}"})
    assert no_host.status == 400  # HTTP/1.1 without a Host: aiohttp's own answer, nothing served
    assert "console" not in no_host.text
    # The token is judged after the Host: a rebinding page cannot spend it.
    assert request(served.port, "/?token=x", {"Host": f"evil.example:{served.port}"}).status == 421
    for host in (f"localhost:{served.port}", f"LOCALHOST.:{served.port}"):
        assert request(served.port, "/", with_cookie(served, cookie, Host=host)).status == 200


@pytest.mark.slow
def test_static_serves_files_never_folders(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    cookie = login.cookie
    headers = with_cookie(served, cookie)
    assert request(served.port, "/static/js/textual.js", headers).status == 200
    for folder in ("/static/", "/static/js", "/static/js/", "/static/css/", "/static/fonts/"):
        answer = request(served.port, folder, headers)
        assert answer.status == 404, folder
        assert b"textual.js" not in answer.body and b"Index of" not in answer.body
    for outside in ("/static/../server.py", "/static/%2e%2e/server.py", "/static//etc/passwd"):
        assert request(served.port, outside, headers).status == 404, outside


@pytest.mark.slow
def test_the_socket_takes_only_its_own_origin(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    cookie = login.cookie
    other = f"http://127.0.0.1:{served.port + 1 if served.port < 65535 else served.port - 1}"
    for origin in (other, "http://evil.example", "null", f"https://{served.host}", None):
        headers = with_cookie(served, cookie)
        if origin is not None:
            headers["Origin"] = origin
        assert handshake(served.port, headers, login.socket) == 403, origin
    own = with_cookie(served, cookie, Origin=served.origin)
    assert (
        handshake(served.port, {"Host": served.host, "Origin": served.origin}, login.socket) == 403
    )
    foreign_host = with_cookie(served, cookie, Host=f"evil.example:{served.port}")
    assert (
        handshake(
            served.port,
            foreign_host | {"Origin": f"http://evil.example:{served.port}"},
            login.socket,
        )
        == 421
    )
    session = Handshake(served.port, own, path=login.socket)
    try:
        assert session.status == 101
    finally:
        session.close()


@pytest.mark.slow
def test_one_session_more_takes_the_slot_and_the_older_is_told(env, running) -> None:
    """The newest page holding the key takes the slot: the older session's socket is
    closed saying so (its page shows it), its console ends before the new one starts."""
    served = start_serve(env, running)
    login = spend_link(served)
    own = with_cookie(served, login.cookie, Origin=served.origin)
    server = served.running.process.pid
    first = Console(served.port, f"{login.socket}?width=100&height=30", own)
    second: Console | None = None
    try:
        first.until("connected")
        assert request(served.port, "/", with_cookie(served, login.cookie)).status == 200
        second = Console(served.port, f"{login.socket}?width=100&height=30", own)
        assert second.status == 101
        assert first.close_frame() == (TAKEN_CODE, TAKEN_REASON)
        second.until("connected")
        assert len(consoles_of(server)) == 1
    finally:
        first.close()
        if second is not None:
            second.close()


@pytest.mark.slow
def test_max_sessions_lets_that_many_in(env, running) -> None:
    served = start_serve(env, running, "--max-sessions", "2")
    login = spend_link(served)
    own = with_cookie(served, login.cookie, Origin=served.origin)
    sessions = [Console(served.port, f"{login.socket}?width=100&height=30", own) for _ in "ab"]
    try:
        for session in sessions:
            session.until("connected")
        sessions.append(Console(served.port, f"{login.socket}?width=100&height=30", own))
        assert sessions[0].close_frame() == (TAKEN_CODE, TAKEN_REASON)  # the oldest
        sessions[2].until("connected")
        sessions[1].type_line("get I 1")
        sessions[1].until("I1 = 1")  # the one in between kept its console
        assert len(consoles_of(served.running.process.pid)) == 2
    finally:
        for session in sessions:
            session.close()


@pytest.mark.slow
def test_it_says_where_and_what_at_start(env, running) -> None:
    served = start_serve(env, running)
    said = "\n".join(served.running.out)
    assert "read-only" in said and "1 session at a time" in said
    assert "reachable from the network" not in said
    assert sum(line.startswith("http://") for line in served.running.out) == 1
    writes = start_serve(env, running, "--allow-writes", "--max-sessions", "3")
    said = "\n".join(writes.running.out)
    assert "writes allowed" in said and "3 sessions at a time" in said
    wide = start_serve(env, running, "--bind", "0.0.0.0")
    assert "reachable from the network" in "\n".join(wide.running.out)
    assert wide.running.stop() == 0


# ------------------------------------------------------------------------- the CLI


@pytest.mark.slow
def test_a_port_taken_is_one_line(env, running) -> None:
    served = start_serve(env, running)
    result = cli(env, "serve", "--port", str(served.port))
    assert result.returncode == 3
    assert f"cannot listen on 127.0.0.1:{served.port}" in one_error_line(result)


def test_without_the_extra_one_line_names_it(env) -> None:
    blocker = (
        "import sys, importlib.abc\n"
        "class Block(importlib.abc.MetaPathFinder):\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in ('aiohttp', 'aiohttp_jinja2', 'textual_serve'):\n"
        "            raise ModuleNotFoundError(name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "from rac_console.cli.main import main\n"
        "sys.exit(main(['serve']))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", blocker], env=env, capture_output=True, text=True, timeout=20
    )
    assert result.returncode == 2
    line = one_error_line(result)
    assert 'pip install "rac-console[web]"' in line


def test_a_broken_config_is_said_once_at_start(env, config) -> None:
    config("[target.x\nhost = ")
    result = cli(env, "serve", "-H", "x", "--port", "0")
    assert result.returncode == 2
    assert "rac-console: " in one_error_line(result)


@pytest.mark.slow
def test_each_session_gets_the_target_as_given(env, running, config) -> None:
    """A profile's name goes to the session as written (the session resolves it)."""
    config(profile("cellsim", 5999))
    served = start_serve(env, running, "-H", "cellsim", "--timeout", "1.5")
    login = spend_link(served)
    cookie = login.cookie
    session = Handshake(
        served.port, with_cookie(served, cookie, Origin=served.origin), path=login.socket
    )
    try:
        assert session.status == 101
        pid = served.running.process.pid
        found: list[str] = []

        def child() -> bool:
            ps = subprocess.run(
                ["ps", "-ww", "-o", "args=", "--ppid", str(pid)], capture_output=True, text=True
            )
            found[:] = [line for line in ps.stdout.splitlines() if "rac_console" in line]
            return bool(found)

        until(child, "the session's console")
        assert found[0].endswith("-P -m rac_console --host=cellsim --timeout=1.5 --read-only")
    finally:
        session.close()


@pytest.mark.parametrize(
    ("words", "said"),
    [
        (["--yes", "serve"], "no --yes"),
        (["serve", "--yes"], "no option --yes"),
        (["--json", "serve"], "no --json"),
        (["serve", "--read-only", "--allow-writes"], "opposite"),
        (["--record", "x.jsonl", "serve"], "no --record"),
        (["serve", "--max-sessions", "0"], "whole number"),
    ],
)
def test_serve_refuses_what_it_cannot_honour(env, words, said) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "rac_console", *words],
        env=env,
        capture_output=True,
        text=True,
        timeout=20,
    )
    assert result.returncode == 2
    assert said in result.stderr
    assert "Traceback" not in result.stderr


def test_the_console_still_needs_a_terminal_unless_served(env) -> None:
    """The served marker alone, or the web driver alone, is not a served session."""
    for extra in ({SERVED_ENV: "1"}, {"TEXTUAL_DRIVER": WEB_DRIVER}):
        result = subprocess.run(
            [sys.executable, "-m", "rac_console"],
            env=env | extra,
            capture_output=True,
            text=True,
            timeout=20,
            stdin=subprocess.DEVNULL,
        )
        assert result.returncode == 2
        assert "needs a terminal" in result.stderr


# ----------------------------------------------------------- the session's command


def test_a_session_runs_a_list_of_arguments_read_only_by_default() -> None:
    argv = session_argv(["--host=cell 3; rm -rf /", "--timeout=1.5"], allow_writes=False)
    assert argv[:4] == (sys.executable, "-P", "-m", "rac_console")
    assert argv[4:] == ("--host=cell 3; rm -rf /", "--timeout=1.5", "--read-only")
    assert session_argv([], allow_writes=True)[-1] == "rac_console"
    with pytest.raises(ValueError):
        session_argv(["-H", "x"], allow_writes=False)  # a value alone could be an option


def test_served_needs_the_driver_and_the_marker() -> None:
    assert served({"TEXTUAL_DRIVER": WEB_DRIVER, SERVED_ENV: "1"})
    assert not served({SERVED_ENV: "1"})
    assert not served({"TEXTUAL_DRIVER": WEB_DRIVER})
    assert not served(
        {"TEXTUAL_DRIVER": "textual.drivers.linux_driver:LinuxDriver", SERVED_ENV: "1"}
    )


# ---------------------------------------------------------------- the guard, pure


@pytest.mark.parametrize(
    ("header", "parts"),
    [
        ("127.0.0.1:8006", ("127.0.0.1", 8006)),
        ("LocalHost.:80", ("localhost", 80)),
        ("[::1]:8006", ("::1", 8006)),
        ("cell-pc", ("cell-pc", None)),
        ("::1", None),
        ("a:b", None),
        ("host:0", None),
        ("host:70000", None),
        ("user@host:1", None),
        ("", None),
        ("[::1", None),
        ("[::1]x", None),
    ],
)
def test_split_host(header, parts) -> None:
    assert split_host(header) == parts


def test_the_host_must_name_this_server() -> None:
    guard = Guard(8006, ["cell-pc.local"])
    assert guard.check_host("cell-pc.local:8006", "192.168.0.5") is None
    assert guard.check_host("192.168.0.5:8006", "192.168.0.5") is None  # the address reached
    assert guard.check_host("192.168.0.6:8006", "192.168.0.5") is not None
    assert guard.check_host("localhost:8006", "192.168.0.5") is not None  # not on loopback
    assert guard.check_host("localhost:8006", "127.0.0.1") is None
    assert guard.check_host("127.0.0.1:8006", "::ffff:127.0.0.1") is None  # dual stack
    assert guard.check_host("[::1]:8006", "::1") is None
    refused = guard.check_host("evil.example:8006", "127.0.0.1")
    assert refused is not None and refused.status == 421
    assert guard.check_host("cell-pc.local", "127.0.0.1") is not None  # port 80 is not ours
    assert Guard(80, ["cell-pc"]).check_host("cell-pc", None) is None


def test_the_origin_must_be_the_servers_own() -> None:
    guard = Guard(8006, ["127.0.0.1"])
    assert guard.check_origin("http://127.0.0.1:8006", "127.0.0.1:8006") is None
    assert guard.check_origin("http://LOCALHOST:8006", "localhost:8006") is None
    for origin in (
        None,
        "",
        "null",
        "http://127.0.0.1:8007",
        "https://127.0.0.1:8006",
        "http://localhost:8006",  # another origin, though the same machine
        "http://127.0.0.1:8006.evil.example",
        "http://127.0.0.1",
    ):
        refused = guard.check_origin(origin, "127.0.0.1:8006")
        assert refused == Refusal(403, refused.reason if refused else ""), origin


def test_the_token_is_spent_once_and_a_wrong_one_spends_nothing() -> None:
    guard = Guard(8006, ["127.0.0.1"], token="t" * 43)
    assert isinstance(guard.exchange("x" * 43), Refusal)
    assert isinstance(guard.exchange(""), Refusal)
    login = guard.exchange("t" * 43)
    assert isinstance(login, Login) and "t" * 43 not in (login.cookie, login.key)
    assert login.cookie != login.key
    assert isinstance(guard.exchange("t" * 43), Refusal)
    cookie = login.cookie
    assert guard.check_cookie(cookie) is None
    assert guard.check_key(cookie, login.key) is None
    assert guard.check_key(cookie, cookie) is not None
    assert guard.check_key(login.key, login.key) is not None
    assert guard.check_key(cookie, "é" * 43) is not None
    assert guard.check_cookie(None) is not None
    assert guard.check_cookie("t" * 43) is not None  # the token is no cookie
    assert guard.cookie_name == "rac_console_8006"


def test_two_guards_have_two_tokens() -> None:
    assert Guard(1, ["a"]).token != Guard(1, ["a"]).token


def test_slots_go_to_the_newest_holders_and_consoles_never_outnumber_them() -> None:
    slots = Slots(2)
    assert slots.claim("a") == [] and slots.claim("b") == []
    assert slots.may_start("a") and slots.may_start("b")
    slots.started()
    slots.started()
    assert slots.claim("c") == ["a"]  # the oldest loses its slot
    assert not slots.holds("a") and slots.holds("c")
    assert not slots.may_start("c")  # a's console still runs
    slots.leave("a", started=True)
    assert slots.may_start("c")
    slots.started()
    assert slots.claim("d") == ["b"]
    assert slots.claim("e") == ["c"]
    assert not slots.may_start("d") and not slots.may_start("e")  # b's and c's end first
    slots.leave("b", started=True)
    assert slots.may_start("d") and slots.may_start("e")
    slots.started()
    assert not slots.may_start("e")  # one console still ending: c's
    with pytest.raises(ValueError):
        Slots(0)


def test_the_guard_is_pure() -> None:
    """No asyncio, sockets or aiohttp in the decisions (a subprocess: a clean import)."""
    code = (
        "import sys, rac_console.serve.guard, rac_console.serve.command\n"
        "bad = {'asyncio', 'socket', 'aiohttp', 'textual_serve'} & set(sys.modules)\n"
        "print(sorted(bad))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=20
    )
    assert result.stdout.strip() == "[]", result.stderr
    assert guard_module.SECRET_BYTES >= 32


# ------------------------------------------------- textual-serve's parts, still there


def test_textual_serve_is_a_version_the_parts_were_checked_against() -> None:
    from rac_console.serve.textual_serve_parts import SUPPORTED

    low = SUPPORTED.split(">=")[1].split(",")[0]
    high = SUPPORTED.split("<")[1]
    installed = tuple(int(n) for n in importlib.metadata.version("textual-serve").split(".")[:3])
    assert (
        tuple(int(n) for n in low.split(".")) <= installed < tuple(int(n) for n in high.split("."))
    )


def test_the_private_parts_relied_on_are_where_they_were() -> None:
    from textual_serve.app_service import AppService
    from textual_serve.server import Server

    from rac_console.serve.textual_serve_parts import RELIES_ON

    assert list(inspect.signature(AppService.__init__).parameters) == [
        "self",
        "command",
        "write_bytes",
        "write_str",
        "close",
        "download_manager",
        "debug",
    ]
    assert list(inspect.signature(AppService._open_app_process).parameters) == [
        "self",
        "width",
        "height",
    ]
    assert list(inspect.signature(AppService._build_environment).parameters) == [
        "self",
        "width",
        "height",
    ]
    source = inspect.getsource(AppService)
    for name in ("self._process", "self._stdin", "self._task"):
        assert name in source, name
    for method in ("start", "stop", "run", "send_bytes", "send_meta"):
        assert inspect.iscoroutinefunction(getattr(AppService, method)), method
    assert list(inspect.signature(AppService.send_bytes).parameters) == ["self", "data"]
    from textual_serve.download_manager import Download, DownloadManager

    assert isinstance(DownloadManager()._active_downloads, dict)
    assert "app_service" in inspect.signature(Download).parameters
    server_init = inspect.signature(Server.__init__).parameters
    assert {"command", "host", "port", "title", "public_url"} <= set(server_init)
    assert list(inspect.signature(Server._process_messages).parameters) == [
        "self",
        "websocket",
        "app_service",
    ]
    assert inspect.iscoroutinefunction(Server.handle_download)
    made = Server("true")
    for name in ("download_manager", "debug", "statics_path", "templates_path", "title"):
        assert hasattr(made, name), name
    template = (Path(made.templates_path) / "app_index.html").read_text(encoding="utf-8")
    for variable in ("font_size", "app_websocket_url", "config.static.url", "application.name"):
        assert variable in template, variable
    assert INLINE_HANDLER in template and template.count("<head>") == 1  # page.dress
    assert re.findall(r"<(?:script|style)\b[^>]*>", template) == [
        '<script src="{{ config.static.url }}js/textual.js">',
        "<style>",
        "<script>",
    ]
    for file in ("js/textual.js", "css/xterm.css"):
        assert (Path(made.statics_path) / file).is_file(), file
    script = (Path(made.statics_path) / "js/textual.js").read_text(encoding="utf-8")
    for part in ("window.onload=", "xterm-helper-textarea", "new WebSocket("):
        assert script.count(part) == 1, part  # what early_keys.py's script counts on
    assert 'this.socket.send(JSON.stringify(["stdin"' in script
    assert len(RELIES_ON) == 14  # a new reliance gets its check here


@pytest.mark.slow
async def test_a_served_console_says_so_on_its_status_line(tmp_path: Path) -> None:
    """A session in a browser is not the console at the cell's own screen: its status line
    starts with SERVED (an unserved console's does not)."""
    from rac_console.engine.setup.where import Where
    from rac_console.tui.status_bar import StatusBar
    from tests.support.drivers import make_app, until

    (tmp_path / "plain").mkdir()
    (tmp_path / "served").mkdir()
    plain = make_app(tmp_path / "plain")
    app = make_app(tmp_path / "served", where=Where.SERVED)
    for console, lead in ((app, True), (plain, False)):
        async with console.run_test(size=(100, 30)) as pilot:
            bar = console.main_screen.panes.status_bar

            def drawn(bar: StatusBar = bar) -> bool:
                return "connected" in bar.line.plain

            await until(pilot, drawn, "the status line")
            assert bar.line.plain.startswith("SERVED ") is lead, bar.line.plain
