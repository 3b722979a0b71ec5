"""``rac-console serve`` put together: the listening socket, the guard's middleware over
textual-serve's routes, the headers every answer carries, and the URL printed once.

The decisions are :mod:`.guard`'s; what is borrowed from textual-serve is
:mod:`.textual_serve_parts`'s; what it says on its standard error goes through
:mod:`.said`; this module only wires them to aiohttp.
"""

from __future__ import annotations

import asyncio
import contextlib
import html
import platform
import signal
import sys
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field

from aiohttp import web, web_response
from aiohttp.typedefs import Middleware

from .guard import BUSY, WILDCARDS, Guard, Refusal, is_loopback, url_host
from .page import DOWNLOAD_POLICY, policy
from .said import Said, listen
from .seats import Seats
from .textual_serve_parts import GuardedServer

#: The port ``serve`` listens on unless told another.
DEFAULT_PORT = 8006

#: What the ``Server`` header says: no version of aiohttp or Python (aiohttp's default
#: names both; its own answers to requests it cannot read use it too).
SERVER_NAME = "rac-console"

#: Sent with every answer: no address (the token's, once) leaves in a Referer; nothing
#: runs inline nor is loaded from anywhere else (:func:`.page.policy`: the page's own
#: answer adds its nonce); no page may frame it (a frame would get the cookie and the
#: socket, and the keys of whoever clicks in it).
HEADERS = {
    "Referrer-Policy": "no-referrer",
    "X-Content-Type-Options": "nosniff",
    "X-Frame-Options": "DENY",
    "Cache-Control": "no-store",
    "Content-Security-Policy": policy(),
    "Server": SERVER_NAME,
}

#: How long an idle kept-alive connection stays open (aiohttp's default is an hour).
KEEPALIVE_SECONDS = 15.0


@dataclass(frozen=True)
class ServeOptions:
    """What ``rac-console serve`` was asked for."""

    argv: Sequence[str]  # each session's command (command.session_argv)
    environment: dict[str, str] = field(default_factory=dict)  # added to each session's
    bind: str = "127.0.0.1"
    port: int = DEFAULT_PORT
    max_sessions: int = 1
    allow_writes: bool = False
    title: str = "rac-console"


def page(status: int, title: str, text: str, extra_head: str = "") -> web.Response:
    body = (
        "<!DOCTYPE html><html><head><meta charset='utf-8'>"
        f"<title>{html.escape(title)}</title>{extra_head}</head>"
        f"<body><h1>{html.escape(title)}</h1><p>{html.escape(text)}</p></body></html>"
    )
    return web.Response(status=status, text=body, content_type="text/html")


def refusal_page(refusal: Refusal) -> web.Response:
    titles = {421: "Misdirected request", 403: "Not allowed"}
    title = "Opened by another page" if refusal.kind == "opener" else None
    return page(refusal.status, title or titles.get(refusal.status, "Refused"), refusal.reason)


def said_refusal(
    said: Said, request: web.Request, refusal: Refusal, detail: str = ""
) -> web.Response:
    """The refusal's page, and a line on this server's standard error (one a kind every
    10 s, :mod:`.said`): whoever runs it sees who was turned away and why (what came
    from the request escaped there)."""
    peer = request.remote or "?"
    path = request.path
    for secret in ("/ws/", "/download/"):  # a key or a download's key: never printed
        if path.startswith(secret):
            path = secret + "…"
    what = f"{request.method} {path}"[:200]
    more = f" ({detail[:200]})" if detail else ""
    said.say(
        f"{refusal.status} {refusal.kind or refusal.reason}",
        f"refused {what} from {peer}: {refusal.status}, {refusal.reason}{more}",
    )
    return refusal_page(refusal)


def local_address(request: web.Request) -> str | None:
    """The address the connection reached on this machine."""
    transport = request.transport
    sockname = transport.get_extra_info("sockname") if transport is not None else None
    if isinstance(sockname, tuple) and sockname:
        return str(sockname[0])
    return None


Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]


def make_middleware(server: ConsoleServer) -> Middleware:
    """Host, then the token or the cookie, then (the page) a free slot."""

    @web.middleware
    async def middleware(request: web.Request, handler: Handler) -> web.StreamResponse:
        guard = server.guard
        if guard is None:  # listening, the link not made yet: nobody can hold it
            return page(BUSY, "Starting", "The server is starting: try again.")
        said = server.said
        host = request.headers.get("Host")
        refused = guard.check_host(host, local_address(request))
        if refused is not None:
            return said_refusal(said, request, refused, f"Host {host!r}")
        cookie = request.cookies.get(guard.cookie_name)
        if request.path == "/" and "token" in request.query and request.method == "GET":
            if guard.has_cookie(cookie):
                return web.Response(status=303, headers={"Location": "/"})
            bought = guard.exchange(request.query["token"])
            if isinstance(bought, Refusal):
                return said_refusal(said, request, bought)
            # The key rides in the fragment: the browser keeps it, no request carries it.
            response = web.Response(status=303, headers={"Location": f"/#key={bought.key}"})
            response.set_cookie(
                guard.cookie_name, bought.cookie, httponly=True, samesite="Strict", path="/"
            )
            return response
        refused = guard.check_cookie(cookie)
        if refused is None and request.path == "/":
            refused = guard.check_opener(request.headers.get("Sec-Fetch-Site"))
        if refused is not None:
            return said_refusal(said, request, refused)
        return await handler(request)

    return middleware


async def add_headers(request: web.Request, response: web.StreamResponse) -> None:
    if request.path.startswith("/download/"):  # a screenshot's SVG: no script, no origin
        response.headers["Content-Security-Policy"] = DOWNLOAD_POLICY
    for name, value in HEADERS.items():
        response.headers.setdefault(name, value)


def own_names(bind: str) -> tuple[str, list[str]]:
    """The name the URL shows, and the names the Host header may use besides the
    address each connection reached (and ``localhost`` on loopback)."""
    if bind in WILDCARDS:
        shown = platform.node() or "localhost"
        return shown, [shown]
    return bind.strip("[]"), [bind]


class ConsoleServer:
    """The server, started and stopped; ``url`` is the one to open (with its token)."""

    def __init__(self, options: ServeOptions, said: Said | None = None) -> None:
        self.options = options
        self.said = said or Said()
        self.guard: Guard | None = None
        self.url = ""
        self._runner: web.AppRunner | None = None
        self.textual: GuardedServer | None = None

    @property
    def port(self) -> int:
        assert self.guard is not None
        return self.guard.port

    async def start(self) -> str:
        """Listen (OSError when the address cannot be had); the link to open."""
        options = self.options
        textual = self.textual = GuardedServer(
            options.argv,
            options.environment,
            make_middleware(self),
            options.title,
            add_headers,
        )
        textual.admit = self._admit
        runner = self._runner = web.AppRunner(
            await textual._make_app(),
            handle_signals=False,
            access_log=None,
            keepalive_timeout=KEEPALIVE_SECONDS,
        )
        await runner.setup()
        # 0.0.0.0 is IPv4's every address, :: IPv6's: each as written (None would be both).
        bind = options.bind.strip("[]") or None
        try:
            await web.TCPSite(runner, bind, options.port, shutdown_timeout=2.0).start()
        except BaseException:
            await self.stop()
            raise
        port = int(runner.addresses[0][1])  # --port 0: the one taken
        shown, names = own_names(options.bind)
        guard = self.guard = Guard(port, names, options.max_sessions)
        textual.seats = Seats(
            guard.slots,
            lambda: self.said.say(
                "taken", "a session was taken by a newer page (its page says so)"
            ),
        )
        textual.key_start = lambda request: guard.key_start(request.cookies.get(guard.cookie_name))
        self.url = f"http://{url_host(shown)}:{port}/?token={guard.token}"
        return self.url

    def _admit(self, request: web.Request, key: str | None) -> web.StreamResponse | None:
        """The socket's own checks, after the middleware's: an upgrade asked for, its
        Origin, the cookie's key (a slot is then taken, :mod:`.seats`)."""
        guard = self.guard
        assert guard is not None  # the middleware let the request through
        if not web.WebSocketResponse().can_prepare(request).ok:
            return page(400, "Not a WebSocket", "this address is the console's socket")
        origin = request.headers.get("Origin")
        refused = guard.check_origin(origin, request.host)
        if refused is not None:
            return said_refusal(self.said, request, refused, f"Origin {origin!r}")
        refused = guard.check_key(request.cookies.get(guard.cookie_name), key)
        if refused is not None:
            return said_refusal(self.said, request, refused)
        return None

    async def stop(self) -> None:
        if self._runner is not None:
            await self._runner.cleanup()
            self._runner = None


def announce(options: ServeOptions, server: ConsoleServer, out: Callable[[str], None]) -> None:
    """What the server says at start: where, what sessions may do, and the URL."""
    writes = (
        "writes allowed (the target's confirm rules apply)"
        if options.allow_writes
        else "read-only (--allow-writes lets writes through)"
    )
    most = options.max_sessions
    sessions = "1 session" if most == 1 else f"{most} sessions"
    out(f"rac-console serve: the console in a browser, {writes}, {sessions} at a time")
    if not is_loopback(options.bind) and options.bind != "localhost":
        out(
            f"rac-console serve: listening on {options.bind}: reachable from the network, "
            "without TLS (the token and the cookie cross it in clear)"
        )
    out("open this link once (it holds a one-time token); Ctrl-C stops the server:")
    out(server.url)


async def serve(options: ServeOptions) -> int:
    """Serve until SIGINT or SIGTERM: 0, or 3 after one line when it cannot listen."""
    said = Said()
    loop = asyncio.get_running_loop()
    unlisten = listen(said, loop)
    # aiohttp's own answers (a 400 for a request it cannot read) name it too
    web_response.SERVER_SOFTWARE = SERVER_NAME  # type: ignore[attr-defined]
    try:
        return await _serve(options, said, loop)
    finally:
        unlisten()
        said.close()


async def _serve(options: ServeOptions, said: Said, loop: asyncio.AbstractEventLoop) -> int:
    server = ConsoleServer(options, said)
    try:
        await server.start()
    except (OSError, OverflowError, UnicodeError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        print(
            f"rac-console: cannot listen on {options.bind}:{options.port}: {reason}",
            file=sys.stderr,
        )
        return 3
    stop = asyncio.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, AttributeError, ValueError):
            loop.add_signal_handler(signum, stop.set)
    announce(options, server, lambda line: print(line, flush=True))
    try:
        await stop.wait()
    finally:
        await server.stop()
    return 0
