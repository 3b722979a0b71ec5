"""The console's page as served: textual-serve's page with our scripts put in, every
inline script and style carrying the answer's nonce (the content security policy has no
``'unsafe-inline'``: a script injected into the page by anything else does not run), and
the closing of a session taken by another page said on it.

Pure text work, no I/O: :mod:`.textual_serve_parts` renders textual-serve's template
and hands the text here.
"""

from __future__ import annotations

import re
import secrets
from collections.abc import Sequence

#: The WebSocket close code of a session whose slot a newer page took (4000-4999: an
#: application's own), and the reason sent with it.
TAKEN_CODE = 4001
TAKEN_REASON = "taken by another page"

#: The close code of a session whose console ended without being asked to (its memory
#: limit, a crash): the reason, which says why, is shown in the "session ended" box.
ENDED_CODE = 4002

#: What the page says, in its "session ended" box, when its session was taken.
TAKEN_TEXT = (
    "Taken by another page: the console was opened in another tab or window of this "
    "browser (rac-console serve lets as many run as --max-sessions). Reload this page "
    "to take it back."
)

#: Every answer's policy but the page's: nothing inline runs; nothing is loaded from
#: or sent to anywhere else (textual-serve's page asks Google for a font: refused, the
#: console falls back to a local monospace); no page may frame it.
_POLICY = (
    "default-src 'self'; script-src 'self'{extra}; style-src 'self'{extra}; "
    "img-src 'self' data:; font-src 'self' data:; connect-src 'self'; base-uri 'none'; "
    "form-action 'none'; frame-ancestors 'none'"
)

#: A file delivered to the browser (a screenshot's SVG opens in it): shown, but in a
#: sandbox of no origin, where no script runs and nothing of the console's is reachable.
DOWNLOAD_POLICY = (
    "sandbox; default-src 'none'; style-src 'unsafe-inline'; img-src data:; "
    "font-src data:; frame-ancestors 'none'"
)

#: textual-serve's buttons call its ``refresh()`` from an ``onClick`` attribute, which a
#: policy without ``'unsafe-inline'`` does not run: the script below listens instead.
INLINE_HANDLER = ' onClick="refresh()"'

#: Listens on textual-serve's buttons, and says on the page why its session closed when
#: a newer page took it or its console ended (the socket's close code and reason); put
#: in the page after the key's.
_SCRIPT = """<script>
(() => {
  for (const button of document.querySelectorAll("button")) {
    button.addEventListener("click", () => refresh());
  }
  const Inner = window.WebSocket;
  class Told extends Inner {
    constructor(...args) {
      super(...args);
      this.addEventListener("close", (event) => {
        if (event.code === ENDED_CODE) {
          const ended = document.querySelector(".closed-dialog .message");
          if (ended) ended.textContent = "Session ended: " + event.reason + ".";
        }
        if (event.code !== TAKEN_CODE) return;
        const message = document.querySelector(".closed-dialog .message");
        if (message) message.textContent = "TAKEN_TEXT";
        const button = document.querySelector(".closed-dialog button");
        if (button) button.textContent = "Take it back";
        document.title = "Taken by another page";
      });
    }
  }
  window.WebSocket = Told;
})();
</script>
"""

PAGE_SCRIPT = (
    _SCRIPT.replace("TAKEN_CODE", str(TAKEN_CODE))
    .replace("TAKEN_TEXT", TAKEN_TEXT)
    .replace("ENDED_CODE", str(ENDED_CODE))
)

#: First in the page's head, before textual.js loads: the ``<style>`` elements the page's
#: own scripts make (xterm.js's theme and cell sizes, the CSS bundled in textual.js)
#: carry the nonce, so they apply; a style put in by anything else does not.
HEAD_SCRIPT = """<script>
(() => {
  const nonce = document.currentScript.nonce;
  const make = Document.prototype.createElement;
  Document.prototype.createElement = function (name, ...rest) {
    const made = make.call(this, name, ...rest);
    if (String(name).toLowerCase() === "style") made.nonce = nonce;
    return made;
  };
})();
</script>
"""


def policy(nonce: str | None = None) -> str:
    """The content security policy; with ``nonce``, the inline scripts and styles that
    carry it run (the page's), and no others."""
    return _POLICY.format(extra=f" 'nonce-{nonce}'" if nonce else "")


def new_nonce() -> str:
    return secrets.token_urlsafe(18)


_INLINE = re.compile(r"<(script|style)>")


def dress(text: str, scripts: Sequence[str], nonce: str) -> str:
    """textual-serve's page with :data:`HEAD_SCRIPT` first in its head, ``scripts`` and
    :data:`PAGE_SCRIPT` before ``</body>``, each inline ``<script>`` and ``<style>``
    carrying ``nonce``, no inline handler."""
    if text.count("</body>") != 1 or text.count("<head>") != 1 or INLINE_HANDLER not in text:
        raise ValueError("textual-serve's page is not the one this module knows")
    text = text.replace(INLINE_HANDLER, "").replace("<head>", "<head>" + HEAD_SCRIPT)
    text = text.replace("</body>", "".join(scripts) + PAGE_SCRIPT + "</body>")
    return _INLINE.sub(lambda m: f'<{m.group(1)} nonce="{nonce}">', text)
