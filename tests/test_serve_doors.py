"""``rac-console serve`` against a client that does not play by a browser's rules: the
cookie replayed from another service of the same host (cookies know no ports), bytes
that are not ASCII where a secret goes, a link spent by a HEAD, a socket asked for with
no upgrade, a package in the folder serve was started
from. Each judged from the server's side: the status it answered, the session it did
or did not start, what it said on its own standard error."""

from __future__ import annotations

import socket
import sys
import tomllib
from pathlib import Path

import pytest

from rac_console.serve.page import TAKEN_CODE, TAKEN_REASON
from tests.support.serving import (
    DEADLINE,
    Console,
    Handshake,
    Login,
    Served,
    alive,
    consoles_of,
    request,
    spend_link,
    start_serve,
    until,
)

pytest.importorskip("textual_serve", reason="needs the extra web")


def own(served: Served, cookie: str) -> dict[str, str]:
    return {
        "Host": served.host,
        "Origin": served.origin,
        "Cookie": f"{served.cookie_name}={cookie}",
    }


@pytest.mark.slow
def test_the_cookie_alone_opens_no_socket(env, running) -> None:
    """Another service on this host gets the cookie from the browser (cookies know no
    ports) and can send any Origin it likes: without the key the page keeps in its own
    origin's storage, it gets no console."""
    served = start_serve(env, running)
    login = spend_link(served)
    cookie, key = login.cookie, login.key
    assert len(key) >= 40 and key not in (cookie, served.token)
    for path in ("/ws", f"/ws/{cookie}", f"/ws/{served.token}", "/ws/x"):
        made = Handshake(served.port, own(served, cookie), path=path)
        made.close()
        assert made.status == 403, path
    other_cookie = Handshake(
        served.port, own(served, "x" * 43) | {"Origin": served.origin}, path=f"/ws/{key}"
    )
    other_cookie.close()
    assert other_cookie.status == 403  # the key is the cookie's own, not a pass alone
    # The page is what carries the key from the fragment to the socket's address.
    index = request(served.port, "/", own(served, cookie))
    assert index.status == 200
    assert key not in index.text
    assert "localStorage" in index.text and "#key=" in index.text
    session = Console(served.port, f"/ws/{key}?width=100&height=30", own(served, cookie))
    try:
        assert session.status == 101
    finally:
        session.close()


@pytest.mark.slow
@pytest.mark.parametrize("where", ["token", "cookie", "key"])
def test_a_secret_that_is_not_ascii_is_refused_not_an_error(env, running, where) -> None:
    served = start_serve(env, running)
    if where == "token":
        answer = request(served.port, "/?token=%C3%A9" + "x" * 40, {"Host": served.host})
    elif where == "cookie":
        headers = own(served, "é" * 43)
        answer = request(served.port, "/", headers)
    else:
        cookie = spend_link(served).cookie
        made = Handshake(served.port, own(served, cookie), path="/ws/%C3%A9" + "x" * 40)
        made.close()
        answer = made.answer
    assert answer.status == 403
    assert "Traceback" not in "\n".join(served.running.err)
    # The real link still works: nothing was spent by the refusal.
    if where != "key":
        spend_link(served)


@pytest.mark.slow
def test_only_a_get_spends_the_link(env, running) -> None:
    served = start_serve(env, running)
    with socket.create_connection(("127.0.0.1", served.port), timeout=DEADLINE) as sock:
        head = f"HEAD /?token={served.token} HTTP/1.1\r\nHost: {served.host}\r\n"
        sock.sendall((head + "Connection: close\r\n\r\n").encode())
        answer = b""
        while chunk := sock.recv(4096):
            answer += chunk
    assert b"Set-Cookie" not in answer
    spend_link(served)  # a link previewer's HEAD left it for the browser


@pytest.mark.slow
def test_asking_for_the_socket_without_an_upgrade_takes_no_slot(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    cookie, key = login.cookie, login.key
    plain = request(served.port, f"/ws/{key}", own(served, cookie))
    assert plain.status == 400
    session = Handshake(served.port, own(served, cookie), path=f"/ws/{key}")
    session.close()
    assert session.status == 101  # the one slot was still free


def open_console(served: Served, login: Login, width: int = 100, height: int = 30) -> Console:
    console = Console(
        served.port, f"{login.socket}?width={width}&height={height}", own(served, login.cookie)
    )
    assert console.status == 101, console.made.answer
    console.send("resize", {"width": width, "height": height})  # as the page does
    return console


@pytest.mark.slow
def test_a_screen_size_no_screen_has_is_brought_within_bounds(env, running) -> None:
    """One message asking for a screen of 3,000 by 3,000 (a browser never sends one):
    the console draws within 1,000 rows, and goes on answering."""
    served = start_serve(env, running)
    console = open_console(served, spend_link(served))
    try:
        console.until("SERVED", "connected")
        console.send("resize", {"width": 3000, "height": 3000})
        console.send("resize", {"width": -5, "height": "x"})  # ignored
        # The same asked as keys (an in-band resize sequence), in two messages.
        console.send("stdin", "\x1b[48;3000")
        console.send("stdin", ";3000;0;0t")
        console.type_line("get I 1")
        console.until("I1 = 1")
        console.until("Quit")  # the footer, on the screen's last row
        assert len(console.screen.rows) <= 1000
    finally:
        console.close()


@pytest.mark.slow
def test_sessions_never_outnumber_max_sessions(env, running) -> None:
    """Sockets opened in a loop, each taking the slot from the one before (the newest
    page wins): a console starts only once the one it displaced has ended, so never two
    run at once, and the newest socket gets the console."""
    served = start_serve(env, running)
    login = spend_link(served)
    server = served.running.process.pid
    path = f"{login.socket}?width=100&height=30"
    sockets = []
    try:
        for _ in range(5):
            sockets.append(Console(served.port, path, own(served, login.cookie)))
            assert sockets[-1].status == 101
            assert len(consoles_of(server)) <= 1
        for older in sockets[:-1]:
            assert older.close_frame() == (TAKEN_CODE, TAKEN_REASON)
            assert len(consoles_of(server)) <= 1
        sockets[-1].until("connected")
        assert len(consoles_of(server)) == 1
    finally:
        for made in sockets:
            made.close()


@pytest.mark.slow
def test_a_session_ends_when_its_server_dies(env, running) -> None:
    """serve killed outright (no chance to end its sessions): each console ends by
    itself, not left polling the controller with nobody to see it."""
    served = start_serve(env, running)
    console = open_console(served, spend_link(served))
    try:
        console.until("SERVED", "connected")
        children = consoles_of(served.running.process.pid)
        assert len(children) == 1
        served.running.process.kill()
        served.running.process.wait(DEADLINE)
        until(lambda: not alive(children[0]), "the orphaned console ending")
    finally:
        console.close()


@pytest.mark.slow
def test_a_refusal_said_on_stderr_does_not_print_the_key(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    foreign = own(served, login.cookie) | {"Origin": "http://evil.example"}
    made = Handshake(served.port, foreign, path=login.socket)
    made.close()
    assert made.status == 403
    until(lambda: any("evil.example" in line for line in served.running.err), "the refusal")
    assert not any(login.key in line for line in served.running.err)


@pytest.mark.slow
def test_sessions_run_the_installed_console_not_a_folder_of_the_same_name(
    env, running, tmp_path: Path
) -> None:
    """serve started in a folder that holds a ``rac_console`` of someone else's: each
    session still runs the installed one."""
    folder = tmp_path / "cwd"
    planted = folder / "rac_console"
    planted.mkdir(parents=True)
    marker = tmp_path / "planted-ran"
    (planted / "__init__.py").write_text("", encoding="utf-8")
    (planted / "__main__.py").write_text(f"open({str(marker)!r}, 'w').close()\n", encoding="utf-8")
    # serve itself started as the installed one (-P): the question is its sessions.
    served = start_serve(
        env, running, cwd=folder, program=(sys.executable, "-P", "-m", "rac_console")
    )
    login = spend_link(served)
    cookie, key = login.cookie, login.key
    console = Console(served.port, f"/ws/{key}?width=100&height=30", own(served, cookie))
    try:
        console.send("resize", {"width": 100, "height": 30})
        console.until("SERVED", "connected")
    finally:
        console.close()
    assert not marker.exists()


@pytest.mark.slow
def test_a_refusal_is_said_on_the_servers_own_error_stream(env, running) -> None:
    """Whoever watches the server sees who was turned away and why, the Origin escaped."""
    served = start_serve(env, running)
    login = spend_link(served)
    cookie, key = login.cookie, login.key
    foreign = own(served, cookie) | {"Origin": "http://evil.example\x9b2J"}
    made = Handshake(served.port, foreign, path=f"/ws/{key}")
    made.close()
    assert made.status == 403

    def said() -> bool:
        return any("refused" in line and "evil.example" in line for line in served.running.err)

    until(said, "the refusal on stderr")
    line = next(line for line in served.running.err if "evil.example" in line)
    assert "\x9b" not in line and "\x1b" not in line and "origin" in line.lower()


def test_ipv4_wildcard_listens_on_ipv4_only(env, running) -> None:
    if not socket.has_ipv6:
        pytest.skip("no IPv6 here")
    try:
        probe = socket.create_server(("::1", 0), family=socket.AF_INET6)
        probe.close()
    except OSError:
        pytest.skip("no IPv6 loopback here")
    served = start_serve(env, running, "--bind", "0.0.0.0")
    with pytest.raises(OSError):
        socket.create_connection(("::1", served.port), timeout=DEADLINE).close()
    with socket.create_connection(("127.0.0.1", served.port), timeout=DEADLINE):
        pass


def test_the_versions_checked_against_are_the_extras_pins() -> None:
    from rac_console.serve.textual_serve_parts import SUPPORTED

    pyproject = tomllib.loads(Path("pyproject.toml").read_text(encoding="utf-8"))
    web = pyproject["project"]["optional-dependencies"]["web"]
    assert SUPPORTED in web
