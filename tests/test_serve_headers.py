"""``rac-console serve``'s answers, header by header: no version in ``Server`` (not even
on aiohttp's own 400), a content security policy without ``'unsafe-inline'`` (the page's
inline scripts and styles carry the answer's nonce), a screenshot delivered in a
sandbox, a bracketed IPv4 Host misdirected, a NUL in a path not found (never a 500), and
a page another site opened told so (``Sec-Fetch-Site``)."""

from __future__ import annotations

import re
import socket

import pytest

from rac_console.serve.guard import Guard, split_host
from tests.support.serving import (
    DEADLINE,
    Console,
    Login,
    Served,
    request,
    spend_link,
    start_serve,
    until,
)

pytest.importorskip("textual_serve", reason="needs the extra web")


def browser(served: Served, login: Login, **more: str) -> dict[str, str]:
    return {"Host": served.host, "Cookie": f"{served.cookie_name}={login.cookie}", **more}


def raw_answer(served: Served, raw: bytes) -> tuple[str, bytes]:
    """``raw`` sent on a connection of its own: the answer's head and body (as sent,
    chunked or not), read until the server closes."""
    with socket.create_connection(("127.0.0.1", served.port), timeout=DEADLINE) as sock:
        sock.sendall(raw)
        answer = b""
        while chunk := sock.recv(65536):
            answer += chunk
    head, _, body = answer.partition(b"\r\n\r\n")
    return head.decode("latin-1"), body


@pytest.mark.slow
def test_no_answer_names_the_servers_versions(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    for answer in (
        request(served.port, "/", browser(served, login)),
        request(served.port, "/", {"Host": served.host}),  # a refusal
        request(served.port, "/static/js/textual.js", browser(served, login)),
    ):
        assert answer.header("server") == "rac-console", answer.headers
    # aiohttp's own answer to a request it cannot read
    head, _ = raw_answer(served, b"GET / HTTP/1.1\r\nHost: x\r\nContent-Length: x\r\n\r\n")
    assert head.startswith("HTTP/1.0 400")
    assert re.search(r"(?im)^server: rac-console\r?$", head), head
    assert "aiohttp" not in head and "Python" not in head


@pytest.mark.slow
def test_the_page_runs_only_its_own_inline_scripts_and_styles(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    index = request(served.port, "/", browser(served, login))
    assert index.status == 200
    policy = index.header("content-security-policy") or ""
    assert "unsafe-inline" not in policy and "unsafe-eval" not in policy
    nonce = re.search(r"script-src 'self' 'nonce-([\w-]+)'", policy)
    assert nonce is not None, policy
    assert f"style-src 'self' 'nonce-{nonce.group(1)}'" in policy
    inline = re.findall(r"<(script|style)( [^>]*)?>", index.text)
    assert len(inline) >= 5  # textual-serve's script and style, ours
    for tag, attributes in inline:
        if "src=" not in attributes:
            assert attributes == f' nonce="{nonce.group(1)}"', (tag, attributes)
    assert "onclick" not in index.text.lower()  # an inline handler would not run
    again = request(served.port, "/", browser(served, login))
    assert nonce.group(1) not in (again.header("content-security-policy") or "")  # per answer
    for other in (
        request(served.port, "/static/js/textual.js", browser(served, login)),
        request(served.port, "/", {"Host": served.host}),
    ):
        assert "unsafe-inline" not in (other.header("content-security-policy") or "unsafe-inline")


@pytest.mark.slow
def test_a_screenshot_opens_in_a_sandbox_not_in_the_consoles_origin(env, running) -> None:
    """The screenshot's SVG is served with a sandbox policy: shown, but with no origin
    (no script of it runs, nothing of the console's is within its reach)."""
    served = start_serve(env, running)
    login = spend_link(served)
    own = browser(served, login, Origin=served.origin)
    console = Console(served.port, f"{login.socket}?width=120&height=40", own)
    try:
        console.until("connected")
        console.send("stdin", "\x10")  # Ctrl+P: the palette
        console.until("Search for commands")
        console.send("stdin", "screenshot")
        console.until("Save an SVG")
        console.send("stdin", "\r")
        delivered = lambda m: isinstance(m, list) and m[0] == "deliver_file_start"  # noqa: E731
        console.until_message(delivered)
        key = next(m[1] for m in console.messages if delivered(m))  # type: ignore[index]
        cookie = f"{served.cookie_name}={login.cookie}"
        head, body = raw_answer(
            served,
            f"GET /download/{key} HTTP/1.1\r\nHost: {served.host}\r\nCookie: {cookie}\r\n"
            "Connection: close\r\n\r\n".encode(),
        )
        assert head.startswith("HTTP/1.1 200"), head
        assert b"<svg" in body[:500]
        found = re.search(r"(?im)^content-security-policy: (.*?)\r?$", head)
        policy = found.group(1) if found else ""
        assert policy.startswith("sandbox;") and "default-src 'none'" in policy, head
        assert "script" not in policy
    finally:
        console.close()


@pytest.mark.slow
def test_a_nul_in_a_static_path_is_not_found_without_a_traceback(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    for path in ("/static/js/textual.js%00", "/static/%00", "/static/js/%00/x"):
        answer = request(served.port, path, browser(served, login))
        assert answer.status == 404, (path, answer.status)
    assert request(served.port, "/static/js/textual.js", browser(served, login)).status == 200
    assert served.running.stop() == 0
    assert not any("Traceback" in line for line in served.running.err), served.running.err


@pytest.mark.slow
def test_a_bracketed_ipv4_host_is_misdirected(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    for host in (f"[127.0.0.1]:{served.port}", f"[localhost]:{served.port}"):
        answer = request(served.port, "/", browser(served, login, Host=host))
        assert answer.status == 421, host
    assert request(served.port, "/", browser(served, login)).status == 200


def test_brackets_hold_an_ipv6_address_and_nothing_else() -> None:
    assert split_host("[127.0.0.1]:8006") is None
    assert split_host("[cell-pc]:8006") is None
    assert split_host("[::ffff:127.0.0.1]:8006") == ("::ffff:127.0.0.1", 8006)
    guard = Guard(8006, ["127.0.0.1"])
    assert guard.check_host("[127.0.0.1]:8006", "127.0.0.1") is not None
    assert guard.check_host("[::1]:8006", "127.0.0.1") is not None  # not the address reached
    assert guard.check_host("[::1]:8006", "::1") is None


@pytest.mark.slow
def test_a_page_another_site_opened_is_told_not_given_the_console(env, running) -> None:
    served = start_serve(env, running)
    login = spend_link(served)
    for site in ("same-site", "cross-site"):
        answer = request(served.port, "/", browser(served, login, **{"Sec-Fetch-Site": site}))
        assert answer.status == 403, site
        assert "Opened by another page" in answer.text
        assert "data-session-websocket-url" not in answer.text
    for site in ("none", "same-origin"):
        answer = request(served.port, "/", browser(served, login, **{"Sec-Fetch-Site": site}))
        assert answer.status == 200, site
    assert request(served.port, "/", browser(served, login)).status == 200  # no such header
    until(
        lambda: any("opened by another page" in line for line in served.running.err),
        "the refusal on stderr",
    )


def test_the_opener_rule() -> None:
    guard = Guard(8006, ["127.0.0.1"])
    for site in ("same-site", "cross-site", "Same-Site "):
        refused = guard.check_opener(site)
        assert refused is not None and refused.status == 403
    for allowed in (None, "", "none", "same-origin"):
        assert guard.check_opener(allowed) is None
