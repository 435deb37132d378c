"""A headless Chromium driven over the DevTools protocol on a pipe (``--remote-debugging-pipe``).

Only the standard library: the browser reads NUL-terminated JSON commands on its fd 3 and
writes replies and events on its fd 4 — no WebDriver, no websocket client. Used by the
report's browser test; Debian's ``/usr/bin/chromium`` (``apt-get install chromium``), run
with no network, no sandbox (root in a container) and a fresh profile.
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import tempfile
import time
from pathlib import Path

CHROMIUM = Path("/usr/bin/chromium")
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars",
         "--mute-audio", "--remote-debugging-pipe")


class Browser:
    """One Chromium process and one page; ``problems`` collects console errors and warnings,
    uncaught exceptions and failed loads (the browser's log entries of level error)."""

    def __init__(self, width: int = 1150, height: int = 900, timeout: float = 60.0):
        self.timeout = timeout
        self._profile = tempfile.TemporaryDirectory(prefix="tiremodal-chromium-")
        c_in, self._w = os.pipe()   # we write commands, Chromium reads fd 3
        self._r, c_out = os.pipe()  # Chromium writes fd 4, we read

        def fds():
            os.dup2(c_in, 3)
            os.dup2(c_out, 4)

        self.proc = subprocess.Popen([str(CHROMIUM), *FLAGS, f"--user-data-dir={self._profile.name}",
                                      f"--window-size={width},{height}", "about:blank"],
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     pass_fds=(3, 4), preexec_fn=fds)
        os.close(c_in)
        os.close(c_out)
        self._buf, self._id, self.events, self.problems = b"", 0, [], []
        target = self.call("Target.createTarget", url="about:blank")["targetId"]
        self.session = self.call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self.call(f"{domain}.enable", session=True)
        self.call("Emulation.setDeviceMetricsOverride", session=True, width=width, height=height,
                  deviceScaleFactor=1, mobile=False)

    # -- protocol
    def _send(self, msg: dict) -> None:
        os.write(self._w, json.dumps(msg).encode() + b"\0")

    def _read(self, deadline: float) -> dict:
        while b"\0" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._r], [], [], left)[0]:
                raise TimeoutError("Chromium did not answer in time")
            chunk = os.read(self._r, 1 << 20)
            if not chunk:
                raise RuntimeError("Chromium closed its DevTools pipe")
            self._buf += chunk
        raw, self._buf = self._buf.split(b"\0", 1)
        msg = json.loads(raw)
        if "method" in msg:
            self._event(msg)
        return msg

    def _event(self, msg: dict) -> None:
        self.events.append(msg["method"])
        p = msg.get("params", {})
        if msg["method"] == "Runtime.consoleAPICalled" and p.get("type") in ("error", "warning", "assert"):
            self.problems.append(f"console.{p['type']}: " + " ".join(str(a.get("value", a.get("description")))
                                                                     for a in p.get("args", [])))
        elif msg["method"] == "Runtime.exceptionThrown":
            self.problems.append("exception: " + p.get("exceptionDetails", {}).get("text", ""))
        elif msg["method"] == "Log.entryAdded" and p.get("entry", {}).get("level") in ("error", "warning"):
            e = p["entry"]
            self.problems.append(f"log {e['level']} ({e.get('source')}): {e.get('text')} {e.get('url', '')}")

    def call(self, method: str, session: bool = False, **params) -> dict:
        self._id += 1
        msg = {"id": self._id, "method": method, "params": params}
        if session:
            msg["sessionId"] = self.session
        self._send(msg)
        deadline = time.monotonic() + self.timeout
        while True:
            r = self._read(deadline)
            if r.get("id") == self._id:
                if "error" in r:
                    raise RuntimeError(f"{method}: {r['error']}")
                return r.get("result", {})

    # -- page
    def open(self, url: str) -> None:
        """Navigate and wait for the load event (every embedded image decoded); ``problems``
        start empty for the new page."""
        n = len(self.events)
        self.problems = []
        self.call("Page.navigate", session=True, url=url)
        deadline = time.monotonic() + self.timeout
        while "Page.loadEventFired" not in self.events[n:]:
            self._read(deadline)

    def js(self, expression: str):
        r = self.call("Runtime.evaluate", session=True, expression=expression, returnByValue=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expression}: {r['exceptionDetails'].get('text')}")
        return r["result"].get("value")

    def screenshot(self, path, *, element_id: str | None = None, height: int = 900) -> Path:
        """A PNG of the page's top, or of ``height`` CSS pixels from the element ``element_id``."""
        import base64

        clip = None
        if element_id:
            box = self.js(f"(() => {{ const r = document.getElementById({json.dumps(element_id)})"
                          ".getBoundingClientRect(); return [r.left + window.scrollX, r.top + window.scrollY, "
                          "document.documentElement.clientWidth]; })()")
            clip = {"x": 0, "y": max(box[1] - 8, 0), "width": box[2], "height": height, "scale": 1}
        kw = {"format": "png"}
        if clip:
            kw.update(clip=clip, captureBeyondViewport=True)
        data = self.call("Page.captureScreenshot", session=True, **kw)["data"]
        Path(path).write_bytes(base64.b64decode(data))
        return Path(path)

    def close(self) -> None:
        try:
            self.call("Browser.close")
        except (RuntimeError, TimeoutError, OSError):
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        os.close(self._w)
        os.close(self._r)
        self._profile.cleanup()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
