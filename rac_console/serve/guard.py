"""Who may come in: the decisions of ``rac-console serve``, without I/O.

Every request is judged in this order, and the first refusal answers it:

1. **Host** (421 Misdirected Request): the Host header must name this server: the
   address it was bound to as written (``--bind cell-pc.local``), the address the
   connection reached (an IP literal), ``localhost`` on a loopback connection, and on a
   wildcard bind (``0.0.0.0``, ``::``) this machine's names; with the server's port. A
   page whose name was rebound to this machine's address (DNS rebinding) sends its own
   name: refused before anything else is looked at.
2. **The token, once** (303 to ``/#key=K``, or 403): ``GET /?token=T`` with the token
   printed at start sets the session cookie and redirects to the page, so the token
   leaves the address bar; it is then spent. The redirect's fragment hands the page
   the cookie's key (below); no request ever carries a fragment. A browser that
   already holds a good cookie is just redirected to ``/``.
3. **The cookie** (403): every other request, pages, files and the WebSocket, needs
   the cookie (HttpOnly, SameSite=Strict). 403, not 401: a cookie is no HTTP
   authentication scheme, there is no challenge to send; the page says what to do.
   **The page's opener** (403, the page only): a page another site sent the browser to
   (``Sec-Fetch-Site: same-site`` or ``cross-site``: a popup or a link of a service on
   another port of this host, which the cookie follows) is not the operator's: it gets
   a page saying so, never the console. The operator's own ways in (the link, the
   address typed, a bookmark, a reload of the console's page) say ``none`` or
   ``same-origin``; a browser that sends no such header is let in (rule 6 then).
4. **Origin** (403, the WebSocket only): exactly this server's own origin
   (``http://`` + the Host just checked). No Origin, or ``null``, is refused as well.
5. **The key** (403, the WebSocket only): the socket's address is ``/ws/KEY``, the
   key handed out with this cookie. Browsers send a cookie to every port of its host,
   so another web service on this machine gets the cookie too, and a program can send
   any Origin: the key is what it lacks. The page keeps it in its own origin's storage,
   which no other port's page can read.
6. **A session slot**: at most ``max_sessions`` sessions hold one, and the newest page
   holding the key takes one: past the limit the oldest session is closed and its page
   says it was taken by another page, so a reload always takes the console back. Its
   console is ended before the new one starts: never more than ``max_sessions``
   consoles at once.

Secrets are compared as bytes in constant time; one that is not ASCII is simply wrong.
"""

from __future__ import annotations

import hmac
import ipaddress
import secrets
from collections.abc import Hashable, Iterable
from dataclasses import dataclass, field

#: The statuses, as the README gives them.
MISDIRECTED = 421
FORBIDDEN = 403
BUSY = 503
NOT_FOUND = 404

#: How many random bytes a token and a cookie hold.
SECRET_BYTES = 32

#: How many characters of a key its page is told, to check a key in its address.
KEY_START = 8

WILDCARDS = frozenset({"0.0.0.0", "::", ""})


@dataclass(frozen=True)
class Refusal:
    """A request turned away: its status, one sentence for the page, and its kind (what
    serve's standard error counts refusals by: a reason may quote the request)."""

    status: int
    reason: str
    kind: str = field(default="", compare=False)


def new_secret() -> str:
    return secrets.token_urlsafe(SECRET_BYTES)


def cookie_name(port: int) -> str:
    """The cookie's name carries the port: browsers keep cookies per host, not per
    port, and two servers on one host must not overwrite each other's."""
    return f"rac_console_{port}"


def split_host(header: str) -> tuple[str, int | None] | None:
    """``name:port``, ``[v6]:port``, ``name`` → (name lowercased without brackets nor a
    final dot, port or None); None when it cannot be a Host."""
    text = header.strip().lower()
    if not text or any(c.isspace() or c in "/\\@?#" for c in text):
        return None
    if text.startswith("["):
        end = text.find("]")
        if end < 0:
            return None
        name, rest = text[1:end], text[end + 1 :]
        if rest and not rest.startswith(":"):
            return None
        if not is_ipv6(name):  # brackets hold an IPv6 address, nothing else ([127.0.0.1])
            return None
        port_text = rest[1:] if rest else None
    else:
        name, colon, port_text_or_empty = text.rpartition(":")
        if not colon:
            name, port_text = text, None
        elif ":" in name:  # a bare IPv6 address is no Host
            return None
        else:
            port_text = port_text_or_empty
    if port_text is not None and not (
        port_text.isascii() and port_text.isdigit() and 0 < int(port_text) < 65536
    ):
        return None
    name = name.rstrip(".")
    if not name:
        return None
    return name, None if port_text is None else int(port_text)


def is_ipv6(text: str) -> bool:
    try:
        return isinstance(ipaddress.ip_address(text), ipaddress.IPv6Address)
    except ValueError:
        return False


def plain_address(address: str) -> str:
    """An address as the Host header writes it: an IPv4-mapped IPv6 address as IPv4."""
    try:
        parsed = ipaddress.ip_address(address.split("%", 1)[0])
    except ValueError:
        return address.lower()
    if isinstance(parsed, ipaddress.IPv6Address) and parsed.ipv4_mapped is not None:
        return str(parsed.ipv4_mapped)
    return str(parsed)


def is_loopback(address: str) -> bool:
    try:
        return ipaddress.ip_address(plain_address(address)).is_loopback
    except ValueError:
        return address.lower() == "localhost"


def url_host(name: str) -> str:
    """A name or address as it goes in a URL: an IPv6 address in brackets."""
    return f"[{name}]" if ":" in name else name


class Slots:
    """Who holds a slot, oldest first, and how many consoles run (a console still ending
    counts). The newest holder wins: one more than ``most`` displaces the oldest, so the
    operator's reload always takes the console back from whatever page held it; a holder
    starts its console only once fewer than ``most`` run."""

    def __init__(self, most: int) -> None:
        if most < 1:
            raise ValueError("at least one session")
        self.most = most
        self.consoles = 0
        self._holders: list[Hashable] = []

    def claim(self, holder: Hashable) -> list[Hashable]:
        """``holder`` holds a slot now; the holders it displaced (oldest first)."""
        self._holders.append(holder)
        displaced = self._holders[: -self.most]
        del self._holders[: -self.most]
        return displaced

    def holds(self, holder: Hashable) -> bool:
        return holder in self._holders

    def may_start(self, holder: Hashable) -> bool:
        """``holder`` still holds its slot and a console may start for it."""
        return self.holds(holder) and self.consoles < self.most

    def started(self) -> None:
        self.consoles += 1

    def leave(self, holder: Hashable, started: bool) -> None:
        """``holder`` is gone, its console (if ``started``) ended."""
        if holder in self._holders:
            self._holders.remove(holder)
        if started:
            self.consoles = max(0, self.consoles - 1)


@dataclass(frozen=True)
class Login:
    """What the link buys: the cookie, and the key the page opens the socket with."""

    cookie: str
    key: str


def same_secret(given: str | None, kept: str) -> bool:
    """``given`` is ``kept``, compared in constant time; never an error (a secret that
    is not ASCII, from a header or a path, is just not the secret)."""
    if not given:
        return False
    return hmac.compare_digest(given.encode("utf-8", "surrogateescape"), kept.encode())


class Guard:
    """The token (spent on first use), the cookies it bought and their keys, the names
    this server answers to and its session slots."""

    def __init__(
        self,
        port: int,
        names: Iterable[str],
        max_sessions: int = 1,
        token: str | None = None,
    ) -> None:
        self.port = port
        self.names = frozenset(plain_address(n.strip("[]")).rstrip(".").lower() for n in names)
        self.token = token or new_secret()
        self.cookie_name = cookie_name(port)
        self.slots = Slots(max_sessions)
        self._token_spent = False
        self._logins: list[Login] = []

    # ------------------------------------------------------------------ Host, Origin

    def check_host(self, header: str | None, local_address: str | None) -> Refusal | None:
        """None when ``header`` names this server (see the module's docstring)."""
        parts = split_host(header or "")
        if parts is None:
            return Refusal(MISDIRECTED, "this request has no Host this server answers to", "host")
        name, port = parts
        if (port if port is not None else 80) != self.port:
            return Refusal(MISDIRECTED, f"this server listens on port {self.port}", "host")
        allowed = set(self.names)
        if local_address:
            local = plain_address(local_address)
            allowed.add(local)
            if is_loopback(local):
                allowed.add("localhost")
        if plain_address(name) not in allowed:
            return Refusal(
                MISDIRECTED,
                f"{name!r} is not a name of this server: open the address rac-console "
                "serve printed",
                "host",
            )
        return None

    def check_origin(self, origin: str | None, host_header: str) -> Refusal | None:
        """None when ``origin`` is this server's own: ``http://`` and the Host the
        request came with (checked before)."""
        refused = Refusal(
            FORBIDDEN, "the console's socket is opened only by its own page", "origin"
        )
        if not origin or not origin.lower().startswith("http://"):  # "null" too
            return refused
        theirs = split_host(origin[len("http://") :])
        ours = split_host(host_header)
        if theirs is None or ours is None:
            return refused
        if (plain_address(theirs[0]), theirs[1] or 80) != (plain_address(ours[0]), ours[1] or 80):
            return refused
        return None

    # --------------------------------------------------------------- token, cookie

    def _login_of(self, cookie: str | None) -> Login | None:
        found = None
        for login in self._logins:  # every one compared: no early exit to time
            if same_secret(cookie, login.cookie):
                found = login
        return found

    def has_cookie(self, value: str | None) -> bool:
        return self._login_of(value) is not None

    def exchange(self, token: str) -> Login | Refusal:
        """The token printed at start, the first time: a new cookie and its key. Spent
        after."""
        if self._token_spent or not same_secret(token, self.token):
            return Refusal(
                FORBIDDEN,
                "this link is not valid (each link opens once): start rac-console serve "
                "again for a new one",
                "token",
            )
        self._token_spent = True
        login = Login(new_secret(), new_secret())
        self._logins.append(login)
        return login

    def key_start(self, cookie: str | None) -> str:
        """The first characters of the key of ``cookie`` ("" for no good cookie): the
        page checks a key in its address against them (48 of the key's 256 bits, told
        only to a request that holds the cookie)."""
        login = self._login_of(cookie)
        return login.key[:KEY_START] if login is not None else ""

    def check_key(self, cookie: str | None, key: str | None) -> Refusal | None:
        """None when ``key`` is the one handed out with ``cookie``."""
        login = self._login_of(cookie)
        if login is not None and same_secret(key, login.key):
            return None
        return Refusal(
            FORBIDDEN,
            "the console's socket opens from its own page, with the key the link gave "
            "it: open the link rac-console serve printed",
            "key",
        )

    def check_cookie(self, value: str | None) -> Refusal | None:
        if self.has_cookie(value):
            return None
        return Refusal(
            FORBIDDEN,
            "open the link rac-console serve printed (with its token) in this browser first",
            "cookie",
        )

    def check_opener(self, fetch_site: str | None) -> Refusal | None:
        """None when the console's page was not opened by another site's page (the
        browser's ``Sec-Fetch-Site``; see the module's docstring)."""
        if (fetch_site or "").strip().lower() not in ("same-site", "cross-site"):
            return None
        return Refusal(
            FORBIDDEN,
            "this page was opened by another page (a popup or a link of a web service "
            "on another port or another host), and the console does not open there: "
            "type its address in the address bar or use a bookmark (a reload of this "
            "tab keeps the other page as its opener)",
            "opener",
        )
