"""The served page's keys from its first moment: the terminal takes the focus as soon as
it exists, and keys typed before the console can take them are delivered, in order, or
said to be lost.

textual-serve's page makes its terminal in ``window.onload`` and never focuses it: keys
typed before a click went nowhere, and keys typed while its socket was still opening
were lost in a ``send`` that threw. The script below (put in the page with the key's,
before textual.js's ``onload``):

- focuses the terminal's input the moment xterm.js adds it (a ``MutationObserver``);
- until then, takes the keys typed into the page itself and keeps them as the terminal
  would send them (letters and signs, Enter, Backspace, Tab, Esc, the arrows, Ctrl and a
  letter); any other key (F-keys, Page Up…) is left to the browser, and a line on the
  page says how many were not sent;
- holds whatever the page sends on its socket while that is still opening (keys,
  focus, size) and sends it, in order, once it opens. The console reads what reached
  it before it started once it has.
"""

from __future__ import annotations

#: The element the page shows the lost keys in (tests read it).
LOST_KEYS_ID = "rac-lost-keys"

_SCRIPT = """<script>
(() => {
  const held = [];  // what the page sends before its socket opens, in order
  const Native = window.WebSocket;
  class Held extends Native {
    constructor(...args) {
      super(...args);
      this.addEventListener("open", () => {
        for (const data of held.splice(0)) super.send(data);
      });
    }
    send(data) {
      if (this.readyState === Native.CONNECTING) held.push(data);
      else super.send(data);
    }
  }
  window.WebSocket = Held;

  const named = {
    Enter: "\\r", Backspace: "\\x7f", Tab: "\\t", Escape: "\\x1b",
    ArrowUp: "\\x1b[A", ArrowDown: "\\x1b[B", ArrowRight: "\\x1b[C", ArrowLeft: "\\x1b[D",
  };
  const modifiers = new Set(["Shift", "Control", "Alt", "Meta", "CapsLock", "AltGraph"]);
  function asTyped(event) {
    if (event.metaKey || event.altKey) return null;
    if (event.ctrlKey) {  // Ctrl and a letter: its control character
      const letter = event.key.toLowerCase();
      return /^[a-z]$/.test(letter) ? String.fromCharCode(letter.charCodeAt(0) - 96) : null;
    }
    if (event.key.length === 1) return event.key;
    return named[event.key] ?? null;
  }
  let lost = 0;
  function early(event) {
    if (modifiers.has(event.key)) return;
    const typed = asTyped(event);
    if (typed === null) {  // the browser's own (F5 reloads), and said not sent
      lost += 1;
      const note = document.getElementById("LOST_KEYS_ID") || document.createElement("div");
      note.id = "LOST_KEYS_ID";
      note.setAttribute("role", "status");
      note.style.cssText = "position:fixed;top:0;left:0;right:0;z-index:100;padding:4px 8px;" +
        "background:#5f0000;color:#fff;font:14px monospace";
      note.textContent = lost + (lost === 1 ? " key" : " keys") + " typed before the " +
        "console was ready could not be sent (" + event.key + "): type " +
        (lost === 1 ? "it" : "them") + " again";
      document.body.appendChild(note);
    } else {  // the console's: the page does nothing with it (Space scrolls no page)
      event.preventDefault();
      event.stopPropagation();
      held.push(JSON.stringify(["stdin", typed]));
    }
  }
  window.addEventListener("keydown", early, true);

  const terminal = document.getElementById("terminal");
  function focusOnce() {
    const input = terminal.querySelector(".xterm-helper-textarea");
    if (!input) return false;
    window.removeEventListener("keydown", early, true);
    input.focus();
    return true;
  }
  if (!focusOnce()) {
    const watching = new MutationObserver(() => { if (focusOnce()) watching.disconnect(); });
    watching.observe(terminal, {childList: true, subtree: true});
  }
})();
</script>
"""

#: The script, ready for the page.
EARLY_KEYS_SCRIPT = _SCRIPT.replace("LOST_KEYS_ID", LOST_KEYS_ID)
