"""The one module that touches textual-serve's private parts (checked against the
versions of :data:`SUPPORTED`; ``tests/test_serve_http.py`` fails when one moves).

What it changes, and why:

- :class:`ExecAppService` starts each session's console with
  ``asyncio.create_subprocess_exec(*argv)``, where textual-serve runs a shell over one
  command string; it adds the served marker to the environment textual-serve builds,
  and a stop that ends a console which does not quit when asked.
- :class:`GuardedServer` keeps textual-serve's page (its template, its static files,
  its message loop between the socket and the console, its downloads) and replaces
  ``_make_app``: the routes it serves, a static route that never lists a folder, the
  page's WebSocket address taken from the request's own Host (the page dressed by
  :mod:`.page`: our scripts, a nonce on every inline script and style), and a socket
  handler that starts an :class:`ExecAppService` once the session sits in a slot
  (:mod:`.seats`). The checks themselves live in :mod:`.guard` and :mod:`.server`,
  which hand this module their middleware.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable, Mapping, Sequence
from functools import partial
from pathlib import Path
from typing import Any

import aiohttp_jinja2
import jinja2
from aiohttp import web
from aiohttp.typedefs import Middleware
from textual_serve.app_service import AppService
from textual_serve.server import Server

from ..present.served import within_screen
from ..present.served_bounds import DROPPED_META, MEMORY_ENV, SentBudget, ended_text
from .early_keys import EARLY_KEYS_SCRIPT
from .page import ENDED_CODE, dress, new_nonce, policy
from .seats import Seat, Seats

log = logging.getLogger("rac_console.serve")

#: The versions of textual-serve this module was written against (pyproject's extra).
SUPPORTED = "textual-serve>=1.1.3,<1.2"

#: What of textual-serve this module relies on; ``tests/test_serve_http.py`` checks each.
RELIES_ON = (
    "textual_serve.app_service.AppService.__init__(command, *, write_bytes, write_str, "
    "close, download_manager, debug)",
    "textual_serve.app_service.AppService._open_app_process(width, height) -> Process",
    "textual_serve.app_service.AppService._build_environment(width, height) -> dict",
    "textual_serve.app_service.AppService._process, ._stdin, ._task",
    "textual_serve.app_service.AppService.start, .stop, .run, .send_bytes(data), .send_meta",
    "textual_serve.download_manager.DownloadManager._active_downloads: key -> Download "
    "(.app_service)",
    "textual_serve.server.Server.__init__(command, host, port, title, public_url)",
    "textual_serve.server.Server._process_messages(websocket, app_service)",
    "textual_serve.server.Server.handle_download, .download_manager, .debug",
    "textual_serve.server.Server.statics_path, .templates_path",
    "templates/app_index.html: font_size, app_websocket_url, config.static.url, application.name",
    'templates/app_index.html: inline <script> and <style> only as such, onClick="refresh()"',
    "static/js/textual.js, static/css/xterm.css",
    "static/js/textual.js: the terminal (its .xterm-helper-textarea) made in window.onload, "
    "its socket a window.WebSocket sent to as keys come (early_keys.py)",
)

#: Put in the page before ``</body>``, so it runs before textual.js's ``onload``: the key
#: the link's redirect put in the fragment goes to this origin's storage (no other
#: port's page reads it) and leaves the address bar; the socket's address ends with it.
#: A fragment key is kept only when it starts as the cookie's key does (KEY_START, the
#: first 8 of its 43 characters): a page elsewhere that sends the browser here with a
#: key of its own in the address does not replace the one kept.
KEY_SCRIPT = """<script>
(() => {
  const found = /^#key=([A-Za-z0-9_-]+)$/.exec(window.location.hash);
  const start = "KEY_START";
  if (found && start.length === 8 && found[1].length === 43 && found[1].startsWith(start)) {
    window.localStorage.setItem("rac-console-key", found[1]);
  }
  if (window.location.hash) {
    window.history.replaceState(null, "", window.location.pathname);
  }
  const key = window.localStorage.getItem("rac-console-key") || "none";
  const terminal = document.getElementById("terminal");
  terminal.dataset.sessionWebsocketUrl += "/" + encodeURIComponent(key);
})();
</script>
"""

#: How long a console has to quit once its socket closed before it is killed.
QUIT_WAIT = 5.0


class ExecAppService(AppService):
    """One session's console, started from a list of arguments (no shell)."""

    def __init__(self, argv: Sequence[str], environment: Mapping[str, str], **options: Any) -> None:
        import shlex

        super().__init__(shlex.join(argv), **options)  # the string is only shown
        self.argv = tuple(argv)
        self.extra_environment = dict(environment)
        self.sent = SentBudget(time.monotonic())
        #: Called with why, when the console ended without being asked to (it ran out
        #: of memory, it crashed): the page's socket is closed, saying so.
        self.ended: Callable[[str], Awaitable[object]] | None = None
        self._stopping = False

    def _build_environment(self, width: int = 80, height: int = 24) -> dict[str, str]:
        return super()._build_environment(width, height) | self.extra_environment

    async def _open_app_process(self, width: int = 80, height: int = 24) -> Any:
        environment = self._build_environment(width=width, height=height)
        self._process = process = await asyncio.create_subprocess_exec(
            *self.argv,
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
            env=environment,
        )
        assert process.stdin is not None
        self._stdin = process.stdin
        return process

    async def set_terminal_size(self, width: int, height: int) -> None:
        """A browser's resize, within what a screen can be: a size that is not a whole
        number is ignored (one message asking for 100,000 rows grew a console by 70 MB
        a second)."""
        if type(width) is int and type(height) is int:
            await super().set_terminal_size(within_screen(width), within_screen(height))

    async def send_bytes(self, data: bytes) -> bool:
        """What the page typed, within the session's bounds (``present/served_bounds.py``):
        a message too big or too fast is dropped, and the console told, which says so."""
        if self.sent.allows(len(data), time.monotonic()):
            return await super().send_bytes(data)
        return await self.send_meta({"type": DROPPED_META, "bytes": len(data)})

    async def run(self) -> None:
        """textual-serve's, until the console's output ends; then, if it ended without
        being asked to, why is said to ``ended`` (its memory limit, a crash)."""
        await super().run()
        process = self._process
        if process is None or self._stopping or self.ended is None:
            return
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(asyncio.shield(process.wait()), QUIT_WAIT)
        limit = self.extra_environment.get(MEMORY_ENV, "")
        mib = int(limit) >> 20 if limit.isdigit() else None
        why = ended_text(process.returncode, mib)
        if why is not None and not self._stopping:
            await self.ended(why)

    @property
    def pid(self) -> int | None:
        return None if self._process is None else self._process.pid

    async def stop(self) -> None:
        """Ask the console to quit; kill it if it has not within :data:`QUIT_WAIT`. The
        files it offered for download go with it (the server kept them, and the session,
        for a download that can no longer come)."""
        self._stopping = True
        try:
            await asyncio.wait_for(super().stop(), QUIT_WAIT)
        except Exception:  # gone already, or deaf: killed at once
            await self.end(grace=0.0)
        else:  # it quit: its output closed, its exit is on the way
            await self.end()
        downloads = self._download_manager._active_downloads
        for key in [key for key, download in downloads.items() if download.app_service is self]:
            del downloads[key]

    async def end(self, grace: float = QUIT_WAIT) -> None:
        """Wait up to ``grace`` for the console to end, kill it if it still runs, and
        wait for it. The wait comes first: a kill looks for the process with a
        ``waitpid`` of its own, which can reap a console that just ended before
        asyncio's watcher does ("Unknown child process pid" on stderr)."""
        process = self._process
        if process is None:
            return
        if process.returncode is None and grace > 0:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(asyncio.shield(process.wait()), grace)
        if process.returncode is None:
            with contextlib.suppress(ProcessLookupError):
                process.kill()
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(process.wait(), QUIT_WAIT)
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await self._task
            self._task = None


class GuardedServer(Server):
    """textual-serve's server with our routes: the page, its socket, its files and
    downloads, behind ``middleware``."""

    def __init__(
        self,
        argv: Sequence[str],
        environment: Mapping[str, str],
        middleware: Middleware,
        title: str,
        on_response_prepare: Callable[[web.Request, web.StreamResponse], Awaitable[None]],
    ) -> None:
        import shlex

        super().__init__(shlex.join(argv), host="127.0.0.1", port=0, title=title)
        self.argv = tuple(argv)
        self.environment = dict(environment)
        self.middleware = middleware
        self.response_prepare = on_response_prepare
        self.services: set[ExecAppService] = set()
        #: Called with the socket's request and the key in its address before a session
        #: starts: a refusal, or None when the session may start.
        self.admit: Callable[[web.Request, str | None], web.StreamResponse | None]
        self.admit = lambda _request, _key: None
        #: The session slots (the newest page holding the key takes one).
        self.seats: Seats | None = None
        #: The first characters of the key of the request's cookie ("" without one).
        self.key_start: Callable[[web.Request], str] = lambda _request: ""

    async def _make_app(self) -> web.Application:
        app = web.Application(middlewares=[self.middleware])
        aiohttp_jinja2.setup(app, loader=jinja2.FileSystemLoader(self.templates_path))
        app.add_routes(
            [
                web.get("/", self.page, name="index"),
                web.get("/ws", self.session, name="websocket"),
                web.get("/ws/{key}", self.session, name="websocket-key"),
                web.get("/download/{key}", self.handle_download, name="download"),
                web.get("/static/{path:.*}", self.static_file, name="static"),
            ]
        )
        app.on_response_prepare.append(self.response_prepare)
        app.on_shutdown.append(self._end_sessions)
        return app

    async def page(self, request: web.Request) -> web.StreamResponse:
        """textual-serve's page, its socket at the address the browser used (the Host
        checked by the middleware), so the socket's Origin is the page's own."""
        host = request.host
        context = {
            "font_size": 16,
            "app_websocket_url": f"ws://{host}/ws",
            "config": {"static": {"url": f"http://{host}/static/"}},
            "application": {"name": self.title},
        }
        response = aiohttp_jinja2.render_template("app_index.html", request, context)
        assert response.text is not None
        script = KEY_SCRIPT.replace("KEY_START", self.key_start(request))
        nonce = new_nonce()
        response.text = dress(response.text, [script, EARLY_KEYS_SCRIPT], nonce)
        response.headers["Content-Security-Policy"] = policy(nonce)
        return response

    async def static_file(self, request: web.Request) -> web.StreamResponse:
        """A file of textual-serve's static folder; a folder, or anything outside it, is
        not found (never a listing)."""
        root = Path(self.statics_path).resolve()
        try:  # a NUL byte in the path is no file (resolve raises ValueError)
            wanted = (root / request.match_info["path"]).resolve()
            found = wanted.is_relative_to(root) and wanted.is_file()
        except (OSError, ValueError):
            found = False
        if not found:
            raise web.HTTPNotFound(text="not found")
        return web.FileResponse(wanted)

    async def session(self, request: web.Request) -> web.StreamResponse:
        """textual-serve's handle_websocket, starting an :class:`ExecAppService` once
        ``admit`` let the session in and it holds a slot (see :mod:`.seats`). The slot is
        given back once its console has ended (not when the socket closed: sockets
        opened and closed in a loop would start consoles faster than they end)."""
        refused = self.admit(request, request.match_info.get("key"))
        if refused is not None:
            return refused
        websocket = web.WebSocketResponse(heartbeat=15)
        seat = Seat(websocket)
        try:
            await websocket.prepare(request)
            if self.seats is None or await self.seats.sit(seat):
                await self._run_session(request, websocket)
        finally:
            if self.seats is not None:
                await self.seats.leave(seat)
        return websocket

    async def _run_session(self, request: web.Request, websocket: web.WebSocketResponse) -> None:
        width = _whole(request.query.get("width"), 80)
        height = _whole(request.query.get("height"), 24)
        service: ExecAppService | None = None
        try:
            service = ExecAppService(
                self.argv,
                self.environment,
                write_bytes=websocket.send_bytes,
                write_str=websocket.send_str,
                close=websocket.close,
                download_manager=self.download_manager,
                debug=self.debug,
            )
            service.ended = partial(_say_ended, websocket)
            self.services.add(service)
            await service.start(width, height)
            await self._process_messages(websocket, service)
        except asyncio.CancelledError:
            await websocket.close()
        except Exception as error:  # one session's failure ends that session alone
            log.warning("session ended: %r", error)
        finally:
            if service is not None:
                await service.stop()
                self.services.discard(service)

    async def _end_sessions(self, _: web.Application) -> None:
        await asyncio.gather(*(service.stop() for service in list(self.services)))


async def _say_ended(websocket: web.WebSocketResponse, why: str) -> None:
    """Close the page's socket with :data:`~.page.ENDED_CODE` and ``why``, which the
    page shows in its "Session ended" box (a close reason is at most 123 bytes)."""
    reason = why.encode("utf-8")[:123].decode("utf-8", "ignore").encode("utf-8")
    with contextlib.suppress(Exception):
        await websocket.close(code=ENDED_CODE, message=reason)


def _whole(text: str | None, default: int) -> int:
    """A size from the query, within what a screen can be."""
    if text is None or not (text.isascii() and text.isdigit()):
        return default
    return within_screen(int(text))
