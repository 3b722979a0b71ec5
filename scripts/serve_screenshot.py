"""screenshots/serve-chromium.png: the console served by ``rac-console serve`` in Debian's
Chromium (driven by playwright), after ``watch IO 0-7`` and ``get I 1``.

Needs the ``web`` extra, playwright and ``/usr/bin/chromium`` (``.ci/run`` installs them):
``python scripts/serve_screenshot.py``. Every wait has a deadline.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

from playwright.sync_api import sync_playwright

OUT = Path(__file__).resolve().parent.parent / "screenshots" / "serve-chromium.png"
DEADLINE = 30.0


def main() -> int:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        print("serve-chromium: needs Debian's chromium (apt install chromium)", file=sys.stderr)
        return 2
    server = subprocess.Popen(
        [sys.executable, "-m", "rac_console", "serve", "--port", "0"],
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "RAC_CONSOLE_ASCII": "0"},
    )
    try:
        assert server.stdout is not None
        url = ""
        end = time.monotonic() + DEADLINE
        while not url.startswith("http://"):
            assert time.monotonic() < end, "no link printed"
            url = server.stdout.readline().strip()
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=chromium)
            page = browser.new_page(viewport={"width": 1280, "height": 760})
            page.goto(url, timeout=DEADLINE * 1000)
            page.wait_for_selector(".xterm-helper-textarea", timeout=DEADLINE * 1000)
            page.wait_for_timeout(2500)  # the first screen, and the simulator connected
            page.focus(".xterm-helper-textarea")  # the keys go to the terminal
            for line in ("watch IO 0-7", "get I 1"):
                page.keyboard.type(line)
                page.keyboard.press("Enter")
                page.wait_for_timeout(800)  # the answer drawn (a picture, not a check)
            page.screenshot(path=str(OUT))
            browser.close()
    finally:
        server.terminate()
        server.wait(timeout=DEADLINE)
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
