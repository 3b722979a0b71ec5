"""``rac-console serve`` in a real browser: Debian's Chromium, driven by Playwright
(``executable_path``: Playwright's own browser download is not used). Skipped where
either is missing (``.ci/run`` installs both).

What the page's terminal shows is read from what its own socket received: an init
script (run before the page's scripts, outside its CSP) tees each message the page's
WebSocket gets, and :class:`~tests.support.drivers.Screen` plays them as a terminal
would. xterm.js draws on a canvas, so there is no text in the DOM to read.
"""

from __future__ import annotations

import http.server
import shutil
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest

from rac_console.serve.early_keys import LOST_KEYS_ID
from tests.support.drivers import Screen, profile
from tests.support.serving import (
    DEADLINE,
    Served,
    consoles_of,
    sim_value,
    start_serve,
    start_sim,
    until,
)

pytest.importorskip("textual_serve", reason="needs the extra web")
playwright_api = pytest.importorskip("playwright.sync_api", reason="needs playwright")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (.ci/run installs it)"),
]

#: Tees what the page's sockets receive into ``window.__racReceived`` (text), and
#: counts the sockets that opened and that failed.
TEE = """
(() => {
  const Real = window.WebSocket;
  const decoder = new TextDecoder();
  window.__racReceived = [];
  window.__racOpened = 0;
  window.__racBlocked = [];  // what the page's content security policy refused
  document.addEventListener("securitypolicyviolation", (event) => {
    window.__racBlocked.push(event.effectiveDirective + " " + (event.blockedURI || "inline"));
  });
  class Tee extends Real {
    constructor(...args) {
      super(...args);
      window.__racSocket = this;  // the newest: a test sends on it as the page would
      this.addEventListener("open", () => { window.__racOpened += 1; });
      this.addEventListener("message", (event) => {
        if (typeof event.data !== "string") {
          window.__racReceived.push(decoder.decode(event.data, {stream: true}));
        }
      });
    }
  }
  window.WebSocket = Tee;
})();
"""

#: A page of another origin that tries the console's socket (the browser holds the
#: cookie: cookies know no ports), even with the key (as if it had learnt it).
FOREIGN_PAGE = """<!DOCTYPE html><html><body><script>
window.result = "pending";
const socket = new WebSocket("ws://127.0.0.1:PORT/ws/KEY?width=80&height=24");
socket.onopen = () => { window.result = "open"; };
socket.onerror = () => { window.result = "error"; };
socket.onclose = (e) => { if (window.result === "pending") window.result = "closed " + e.code; };
</script></body></html>"""


#: Whether the page's focus is in its terminal (xterm.js's input).
TERMINAL_FOCUSED = "document.activeElement?.classList.contains('xterm-helper-textarea')"

#: Opens a socket from the page it runs in: "open" or "error".
OPEN_SOCKET = """(url) => new Promise((resolve) => {
  const socket = new WebSocket(url + "?width=80&height=24");
  socket.onopen = () => { resolve("open"); socket.close(); };
  socket.onerror = () => resolve("error");
  setTimeout(() => resolve("neither opened nor failed"), 20000);
})"""


class ServedPage:
    """The console's page in the browser, its terminal as text."""

    def __init__(self, page: Any) -> None:
        self.page = page
        self.screen = Screen(1000)  # Textual moves the cursor absolutely: no wrapping

    def text(self) -> str:
        received = self.page.evaluate("window.__racReceived.splice(0)")
        self.screen.feed("".join(received))
        return "\n".join(self.screen.lines())

    def until(self, *texts: str, timeout: float = DEADLINE) -> str:
        end = time.monotonic() + timeout
        while True:
            shown = self.text()
            if all(text in shown for text in texts):
                return shown
            if time.monotonic() > end:
                raise AssertionError(f"timed out waiting for {texts} on the page:\n{shown}")
            self.page.wait_for_timeout(50)

    def type_line(self, line: str) -> None:
        self.page.keyboard.type(line)
        self.page.keyboard.press("Enter")


@pytest.fixture
def browser() -> Iterator[Any]:
    with playwright_api.sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=CHROMIUM, headless=True)
        try:
            yield launched
        finally:
            launched.close()


def open_console(context: Any, served: Served) -> ServedPage:
    """The printed link opened in ``context``; the console's first screen on it."""
    page = context.new_page()
    page.add_init_script(TEE)
    page.goto(served.url, wait_until="domcontentloaded", timeout=DEADLINE * 1000)
    console = ServedPage(page)
    console.until("rac-console")
    # The terminal took the focus when it was made: the keys go to it, no click needed.
    assert page.evaluate(TERMINAL_FOCUSED), "the terminal does not have the focus"
    return console


class ForeignSite:
    """Another origin on the same host: a page whose script tries the console's socket."""

    def __init__(self, port: int, key: str, page: str = FOREIGN_PAGE) -> None:
        body = page.replace("PORT", str(port)).replace("KEY", key).encode()

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self) -> None:
                self.send_response(200)
                self.send_header("Content-Type", "text/html")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *args: object) -> None:
                pass

        self.server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.port = self.server.server_address[1]
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


def result_of(page: Any) -> str:
    end = time.monotonic() + DEADLINE
    while (result := page.evaluate("window.result")) == "pending":
        if time.monotonic() > end:
            raise AssertionError("the socket neither opened nor failed")
        page.wait_for_timeout(50)
    return str(result)


def test_the_console_renders_and_takes_keys_through_the_link(env, running, browser, tmp_path):
    served = start_serve(env, running)
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    console = open_console(context, served)
    page = console.page
    assert page.url == served.origin + "/"  # the token and the key left the address bar
    assert page.evaluate("document.cookie") == ""  # HttpOnly: no script reads it
    assert len(page.evaluate("localStorage.getItem('rac-console-key')")) >= 40
    shown = console.until("SIMULATOR", "READ-ONLY")
    assert "Watch" in shown
    console.type_line("get I 1")
    console.until("I1 = 1")
    page.screenshot(path=str(tmp_path / "console.png"))
    # No 'unsafe-inline': the page's own scripts and styles ran (the nonce); only the
    # font textual-serve asks Google for was refused.
    blocked = page.evaluate("window.__racBlocked")
    assert [b for b in blocked if "fonts.googleapis.com" not in b] == [], blocked
    # The link opens once: a second browser with it gets nothing.
    other = browser.new_context().new_page()
    answer = other.goto(served.url, timeout=DEADLINE * 1000)
    assert answer is not None and answer.status == 403


def test_a_page_of_another_origin_holding_the_cookie_cannot_open_the_socket(env, running, browser):
    served = start_serve(env, running, "--max-sessions", "2")
    context = browser.new_context()
    console = open_console(context, served)
    key = console.page.evaluate("localStorage.getItem('rac-console-key')")
    foreign = ForeignSite(served.port, key)
    try:
        cookies = {c["name"]: c for c in context.cookies(f"http://127.0.0.1:{foreign.port}/")}
        assert served.cookie_name in cookies  # the browser would send it along
        page = context.new_page()
        page.goto(f"http://127.0.0.1:{foreign.port}/", timeout=DEADLINE * 1000)
        assert result_of(page) == "error"
        # Turned away for its Origin (the cookie and the key were there), as the server says.
        foreign_origin = f"http://127.0.0.1:{foreign.port}"
        until(
            lambda: any(
                "refused" in line and f"Origin {foreign_origin!r}" in line
                for line in served.running.err
            ),
            "the refusal of the foreign Origin on the server's stderr",
        )
        # The same socket from the console's own page opens (a slot was free for both).
        assert console.page.evaluate(OPEN_SOCKET, f"ws://{served.host}/ws/{key}") == "open"
    finally:
        foreign.close()


def test_put_in_a_default_session_is_refused(env, running, browser):
    sim_port = start_sim(env, running)
    before = sim_value(env, sim_port, "I 10")
    served = start_serve(env, running, before=("-H", "127.0.0.1", "-p", str(sim_port)))
    console = open_console(browser.new_context(), served)
    console.until("READ-ONLY")
    console.type_line("put I 10 5")
    console.until("read-only mode is on")
    assert sim_value(env, sim_port, "I 10") == before != 5


def test_with_allow_writes_a_confirmed_write_lands(env, running, browser, config):
    sim_port = start_sim(env, running)
    config(profile("cellsim", sim_port, 'writes = "confirm"'))
    assert sim_value(env, sim_port, "I 10") != 5
    served = start_serve(env, running, "-H", "cellsim", "--allow-writes")
    console = open_console(browser.new_context(), served)
    shown = console.until("cellsim")
    assert "READ-ONLY" not in shown
    console.type_line("put I 10 5")
    console.until("[y/N]")  # shown once a y counts (until then the question says …)
    assert sim_value(env, sim_port, "I 10") != 5  # nothing written before the answer
    console.page.keyboard.press("y")
    console.until("read back 5")
    assert sim_value(env, sim_port, "I 10") == 5


def test_keys_typed_before_the_terminal_exists_reach_the_console_or_are_said_lost(
    env, running, browser
):
    """The page's load is held (its background image not yet answered): the terminal
    does not exist, nothing has the focus, and keys typed then go to the page. Once it
    loads, the terminal has the focus, the line typed runs, and the key that could not
    be kept (Page Down) is said on the page."""
    served = start_serve(env, running)
    page = browser.new_context().new_page()
    page.add_init_script(TEE)
    held: list[Any] = []
    page.route("**/images/background.png", lambda route: held.append(route))
    page.goto(served.url, wait_until="domcontentloaded", timeout=DEADLINE * 1000)
    end = time.monotonic() + DEADLINE
    while not held:  # Playwright calls the route's handler while the test waits in it
        assert time.monotonic() < end, "the page never asked for its background"
        page.wait_for_timeout(50)
    assert page.query_selector(".xterm-helper-textarea") is None  # no terminal yet
    page.keyboard.type("get I 1")
    page.keyboard.press("PageDown")
    page.keyboard.press("Enter")
    assert page.query_selector(".xterm-helper-textarea") is None  # typed before it
    held[0].continue_()
    console = ServedPage(page)
    console.until("I1 = 1")
    assert page.evaluate(TERMINAL_FOCUSED)
    lost = page.inner_text(f"#{LOST_KEYS_ID}")
    assert "1 key typed before the console was ready could not be sent (PageDown)" in lost


def test_a_key_planted_in_the_address_does_not_replace_the_one_kept(env, running, browser):
    """A page elsewhere sends the browser to the console's address with a key of its own
    in the fragment: the console's page keeps the key the link gave it, and opens."""
    served = start_serve(env, running, "--max-sessions", "2")
    context = browser.new_context()
    first = open_console(context, served)
    key = first.page.evaluate("localStorage.getItem('rac-console-key')")
    planted = context.new_page()
    planted.add_init_script(TEE)
    planted.goto(f"{served.origin}/#key={'j' * 43}", timeout=DEADLINE * 1000)
    console = ServedPage(planted)
    console.until("rac-console", "connected")
    assert planted.evaluate("localStorage.getItem('rac-console-key')") == key


#: A page of another port of this host whose button opens the console in a popup (one
#: click: popups need one). Same site, so the browser sends the console's cookie along,
#: and the popup is the console's own page: its storage holds the key.
POPUP_PAGE = """<!DOCTYPE html><html><body>
<button id="open" onclick="window.popup = window.open('http://127.0.0.1:PORT/', 'console')">
open</button></body></html>"""


def console_sockets(page: Any) -> int:
    """How many sockets the page opened (TEE counts them)."""
    return int(page.evaluate("window.__racOpened ?? 0"))


def tab(context: Any, url: str) -> ServedPage:
    """A new tab of ``context`` (whose every page tees its sockets) at ``url``, as typed."""
    page = context.new_page()
    page.goto(url, wait_until="domcontentloaded", timeout=DEADLINE * 1000)
    return ServedPage(page)


def closed_with(page: Any) -> str:
    """What the page's "session ended" box says, once it shows."""
    page.wait_for_function("document.body.classList.contains('-closed')", timeout=DEADLINE * 1000)
    return str(page.inner_text(".closed-dialog .message"))


def test_a_page_of_another_port_cannot_keep_the_operator_out(env, running, browser):
    """A service on another port of this host opens the console in a popup while the
    operator's tab is closed: the popup gets no console (another page opened it, which
    the browser says), and the operator, opening the console's address again, gets it."""
    served = start_serve(env, running, "--max-sessions", "1")
    context = browser.new_context()
    context.add_init_script(TEE)  # the popup's too
    operator = tab(context, served.url)
    operator.until("rac-console", "connected")
    operator.page.close()
    until(lambda: consoles_of(served.running.process.pid) == [], "the operator's console ended")
    foreign = ForeignSite(served.port, "", POPUP_PAGE)
    try:
        page = context.new_page()
        page.goto(f"http://127.0.0.1:{foreign.port}/", timeout=DEADLINE * 1000)
        with page.expect_popup() as opened:
            page.click("#open")
        popup = opened.value
        popup.wait_for_load_state("domcontentloaded", timeout=DEADLINE * 1000)
        # The operator types the console's address in a new tab.
        again = tab(context, served.origin + "/")
        again.until("rac-console", "connected")
        assert console_sockets(popup) == 0, popup.content()
        assert "opened by another page" in popup.inner_text("body")
        assert len(consoles_of(served.running.process.pid)) == 1
    finally:
        foreign.close()


def test_the_newest_page_takes_the_console_and_the_older_page_says_so(env, running, browser):
    """Two tabs of the operator's browser, one slot: the newer tab gets the console, the
    older one says it was taken by another page, and its reload takes the console back
    (the other tab then says so). Never two consoles at once."""
    served = start_serve(env, running, "--max-sessions", "1")
    server = served.running.process.pid
    context = browser.new_context()
    context.add_init_script(TEE)
    first = tab(context, served.url)
    first.until("rac-console", "connected")
    second = tab(context, served.origin + "/")
    second.until("rac-console", "connected")
    assert "Taken by another page" in closed_with(first.page)
    assert len(consoles_of(server)) == 1
    first.page.reload(wait_until="domcontentloaded", timeout=DEADLINE * 1000)
    back = ServedPage(first.page)  # a new page: a new screen
    back.until("rac-console", "connected")
    back.type_line("get I 1")
    back.until("I1 = 1")
    assert "Taken by another page" in closed_with(second.page)
    assert len(consoles_of(server)) == 1


def test_a_console_at_its_memory_limit_ends_and_its_page_says_why(env, running, browser, tmp_path):
    """The session's console passes its memory limit (a screen of 1,000 x 1,000 and a
    watch, under a limit of 128 MiB): the page's "session ended" box says why."""
    served = start_serve(env, running, "--session-memory", "128")
    console = open_console(browser.new_context(), served)
    console.until("connected")
    resize = "['resize', {width: 1000, height: 1000}]"
    console.page.evaluate(f"window.__racSocket.send(JSON.stringify({resize}))")
    console.type_line("watch T 0-255")
    closed = "document.body.classList.contains('-closed')"
    until(lambda: bool(console.page.evaluate(closed)), "the session ended")
    said = console.page.inner_text(".closed-dialog .message")
    console.page.screenshot(path=str(tmp_path / "ended.png"))
    assert said == (
        "Session ended: the console reached its memory limit of 128 MiB and ended "
        "(rac-console serve --session-memory)."
    )
    until(lambda: consoles_of(served.running.process.pid) == [], "the console gone")
