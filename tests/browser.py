"""A headless Chromium driven over the DevTools protocol, for end-to-end tests of HTML pages.

``find_chromium()`` looks for a browser (``LAMP_CHROMIUM``, then ``chromium``,
``chromium-browser``, ``google-chrome`` on the PATH); ``Browser`` starts it with a fresh
profile and no network services, opens one page and offers ``open``, ``evaluate`` and
``screenshot``. The protocol runs over a local websocket (the ``websockets`` package).
"""

from __future__ import annotations

import base64
import contextlib
import itertools
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Any

INSTALL_HINT = ("no Chromium found: install it (Debian/Ubuntu: `apt-get install chromium`) "
                "or point LAMP_CHROMIUM at a Chromium/Chrome binary")

FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-extensions", "--disable-default-apps", "--mute-audio",
         "--hide-scrollbars", "--force-device-scale-factor=1", "--remote-allow-origins=*",
         "--disable-dev-shm-usage")  # containers often have a tiny /dev/shm


def find_chromium() -> str | None:
    env = os.environ.get("LAMP_CHROMIUM")
    if env:
        return env
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Browser:
    """One headless Chromium with one page of ``width`` x ``height`` CSS pixels, ``scale``
    device pixels per CSS pixel (a HiDPI screen for ``scale`` 2)."""

    def __init__(self, binary: str, width: int = 1280, height: int = 800,
                 timeout: float = 30.0, scale: float = 1.0) -> None:
        from websockets.sync.client import connect

        self.timeout = timeout
        self._stack = contextlib.ExitStack()
        self._profile = tempfile.mkdtemp(prefix="lamp-chromium-")
        self._proc = subprocess.Popen(
            [binary, *FLAGS, f"--user-data-dir={self._profile}", "--remote-debugging-port=0",
             f"--window-size={width},{height}", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            port = self._port()
            page = self._page_target(port)
            self._ws = self._stack.enter_context(
                connect(page["webSocketDebuggerUrl"], max_size=None, open_timeout=timeout))
        except BaseException:
            self.close()
            raise
        self._ids = itertools.count(1)
        self.call("Page.enable")
        self.call("Runtime.enable")
        self.call("Emulation.setDeviceMetricsOverride", width=width, height=height,
                  deviceScaleFactor=scale, mobile=False)

    def _port(self) -> int:
        marker = Path(self._profile) / "DevToolsActivePort"
        end = time.monotonic() + self.timeout
        while time.monotonic() < end:
            if self._proc.poll() is not None:
                raise RuntimeError(f"chromium exited with status {self._proc.returncode}")
            if marker.is_file():
                lines = marker.read_text().split()
                if lines:
                    return int(lines[0])
            time.sleep(0.05)
        raise TimeoutError("chromium did not open its DevTools port")

    def _page_target(self, port: int) -> dict[str, Any]:
        end = time.monotonic() + self.timeout
        while time.monotonic() < end:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5) as r:
                pages = [t for t in json.load(r) if t.get("type") == "page"]
            if pages:
                return pages[0]
            time.sleep(0.05)
        raise TimeoutError("chromium opened no page")

    def call(self, method: str, **params: Any) -> dict[str, Any]:
        """Send one protocol command and return its result (events on the way are dropped,
        except that ``Page.loadEventFired`` is remembered for ``open``)."""
        msg_id = next(self._ids)
        self._ws.send(json.dumps({"id": msg_id, "method": method, "params": params}))
        end = time.monotonic() + self.timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no answer to {method}")
            msg = json.loads(self._ws.recv(timeout=left))
            if msg.get("method") == "Page.loadEventFired":
                self._loaded = True
            if msg.get("id") == msg_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})

    def open(self, url: str) -> None:
        """Navigate to ``url`` and wait for its load event (a new document: a change of the
        fragment alone loads nothing, so open another page in between)."""
        self._loaded = False
        self.call("Page.navigate", url=url)
        end = time.monotonic() + self.timeout
        while not self._loaded:
            if time.monotonic() > end:
                raise TimeoutError(f"{url} did not load")
            msg = json.loads(self._ws.recv(timeout=max(end - time.monotonic(), 0.01)))
            if msg.get("method") == "Page.loadEventFired":
                self._loaded = True

    def evaluate(self, expression: str) -> Any:
        """The JSON value of a JavaScript expression in the page (exceptions re-raised)."""
        res = self.call("Runtime.evaluate", expression=expression, returnByValue=True,
                        awaitPromise=True)
        if "exceptionDetails" in res:
            raise RuntimeError(f"{expression}: {res['exceptionDetails']}")
        return res["result"].get("value")

    def mouse(self, kind: str, x: float, y: float, **params: Any) -> None:
        """A real mouse event at page coordinates (``mousePressed``, ``mouseMoved``,
        ``mouseReleased``, ``mouseWheel``), as the user's input would arrive."""
        self.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, **params)

    def screenshot(self) -> bytes:
        """The page as PNG bytes."""
        return base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])

    def close(self) -> None:
        self._stack.close()
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def main(argv: list[str]) -> int:
    """``python tests/browser.py PAGE.html OUT.png [FRAGMENT]``: a screenshot of a page
    (how the README's picture of the replay viewer is made)."""
    if len(argv) not in (2, 3):
        print(main.__doc__)
        return 2
    binary = find_chromium()
    if binary is None:
        print(INSTALL_HINT)
        return 2
    page = Path(argv[0]).resolve().as_uri() + (argv[2] if len(argv) == 3 else "")
    with Browser(binary, width=1280, height=760) as b:
        b.open(page)
        Path(argv[1]).write_bytes(b.screenshot())
    return 0


if __name__ == "__main__":
    import sys

    raise SystemExit(main(sys.argv[1:]))
