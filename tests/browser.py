"""A headless Chromium driven over the Chrome DevTools protocol on a pipe (--remote-debugging-pipe):
the protocol's JSON messages, NUL-separated, on file descriptors 3 (to the browser) and 4 (from
it). No websocket client, no chromedriver and no Python package beyond the standard library:
Debian's ``chromium`` is all it needs. The mouse events it sends (``Input.dispatchMouseEvent``)
are the browser's own trusted input events, the ones a person's clicks make."""
from __future__ import annotations

import fcntl
import json
import os
import select
import shutil
import subprocess
import tempfile
import time

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


class BrowserError(RuntimeError):
    pass


class Chromium:
    def __init__(self, width: int = 1440, height: int = 1200):
        to_r, to_w = os.pipe()      # the browser reads commands on fd 3
        from_r, from_w = os.pipe()  # and writes answers and events on fd 4
        to_r, from_w = (self._high(fd) for fd in (to_r, from_w))  # clear of 3 and 4 for the shell's moves
        self.profile = tempfile.mkdtemp(prefix="spreadmap-chromium-")
        args = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--no-first-run", "--hide-scrollbars",
                f"--user-data-dir={self.profile}", "--remote-debugging-pipe", f"--window-size={width},{height}",
                "about:blank"]
        shell = f'exec "$@" 3<&{to_r} 4>&{from_w} {to_r}<&- {from_w}>&-'
        self.proc = subprocess.Popen(["bash", "-c", shell, "bash", *args], pass_fds=(to_r, from_w),
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_r)
        os.close(from_w)
        self.out, self.inp = to_w, from_r
        self.buffer, self.last_id, self.session = b"", 0, None

    @staticmethod
    def _high(fd: int) -> int:
        high = fcntl.fcntl(fd, fcntl.F_DUPFD, 10)
        os.close(fd)
        return high

    def _message(self, deadline: float) -> dict:
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.inp], [], [], left)[0]:
                raise BrowserError("no answer from chromium in time")
            chunk = os.read(self.inp, 1 << 20)
            if not chunk:
                raise BrowserError(f"chromium closed its pipe (exit code {self.proc.poll()})")
            self.buffer += chunk
        raw, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(raw)

    def send(self, method: str, params: dict | None = None, session: bool = True, timeout: float = 60) -> dict:
        self.last_id += 1
        message = {"id": self.last_id, "method": method, "params": params or {}}
        if session and self.session:
            message["sessionId"] = self.session
        os.write(self.out, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            answer = self._message(deadline)
            if answer.get("id") == self.last_id:
                if "error" in answer:
                    raise BrowserError(f"{method}: {answer['error']}")
                return answer["result"]

    def open(self, url: str) -> None:
        target = self.send("Target.createTarget", {"url": "about:blank"}, session=False)["targetId"]
        self.session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True}, session=False)["sessionId"]
        self.send("Page.navigate", {"url": url})

    def evaluate(self, expression: str):
        result = self.send("Runtime.evaluate", {"expression": expression, "returnByValue": True})
        if "exceptionDetails" in result:
            raise BrowserError(f"{expression[:80]}...: {result['exceptionDetails'].get('exception', {}).get('description')}")
        return result["result"].get("value")

    def wait_for(self, expression: str, timeout: float = 60.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            value = self.evaluate(expression)
            if value:
                return value
            time.sleep(0.1)
        raise BrowserError(f"timed out waiting for: {expression}")

    def click(self, x: float, y: float) -> None:
        """A left click at page pixel (x, y): move there, press, release."""
        base = {"x": float(x), "y": float(y)}
        self.send("Input.dispatchMouseEvent", {"type": "mouseMoved", **base})
        self.send("Input.dispatchMouseEvent", {"type": "mousePressed", "button": "left", "buttons": 1, "clickCount": 1, **base})
        self.send("Input.dispatchMouseEvent", {"type": "mouseReleased", "button": "left", "buttons": 0, "clickCount": 1, **base})

    def close(self) -> None:
        try:
            self.send("Browser.close", session=False, timeout=10)
        except (BrowserError, OSError):
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        for fd in (self.out, self.inp):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
