"""Headless Chromium for the tests that read pages in a real browser (the grade site, the run's
page, the notebook's output): a driver over Chrome's DevTools protocol on a pipe (no network, no
extra package), and :data:`BROWSERS`, the names it is found by. The ``browser`` fixture (one
Chromium for the whole session) is in conftest.py."""

from __future__ import annotations

import base64
import contextlib
import fcntl
import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

BROWSERS = ("chromium", "chromium-browser", "google-chrome")

FLAGS = (
    "--headless=new",
    "--no-sandbox",  # CI runs as root
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-extensions",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--mute-audio",
    "--remote-debugging-pipe",
)


# puts the pipe's ends on fds 3 and 4, where --remote-debugging-pipe wants them, then becomes Chromium
LAUNCH = (
    "import os, sys\n"
    "fd_in, fd_out = int(sys.argv[1]), int(sys.argv[2])\n"
    "os.dup2(fd_in, 3); os.dup2(fd_out, 4); os.close(fd_in); os.close(fd_out)\n"
    "os.execv(sys.argv[3], sys.argv[3:])\n"
)


class Chromium:
    """Headless Chromium over the DevTools protocol on a pipe: it reads commands on its fd 3 and
    writes answers and events on its fd 4, each a JSON text ended by a NUL byte."""

    def __init__(self, exe: str, profile: Path) -> None:
        to_r, self._w = os.pipe()
        self._r, from_w = os.pipe()
        # the child's ends, numbered 10 and up so that moving them to 3 and 4 clobbers nothing
        child_in, child_out = fcntl.fcntl(to_r, fcntl.F_DUPFD, 10), fcntl.fcntl(from_w, fcntl.F_DUPFD, 10)
        os.close(to_r)
        os.close(from_w)
        self.log = profile / "chromium.log"
        with self.log.open("wb") as log:
            self.proc = subprocess.Popen(
                [
                    sys.executable,
                    "-c",
                    LAUNCH,
                    str(child_in),
                    str(child_out),
                    exe,
                    *FLAGS,
                    f"--user-data-dir={profile / 'profile'}",
                ],
                pass_fds=(child_in, child_out),
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=log,
                start_new_session=True,
            )
        os.close(child_in)
        os.close(child_out)
        self._buffer = b""
        self._ids = 0
        self.events: list[dict[str, Any]] = []

    def _receive(self, deadline: float) -> dict[str, Any]:
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._r], [], [], left)[0]:
                raise TimeoutError(f"Chromium did not answer (log: {self.log})")
            chunk = os.read(self._r, 1 << 20)
            if not chunk:
                raise RuntimeError(f"Chromium closed the pipe: {self.log.read_text(errors='replace')[-2000:]}")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def call(self, method: str, params: dict[str, Any] | None = None, session: str | None = None) -> dict[str, Any]:
        """Send a command and wait (30 s at most) for its answer; events met on the way are kept."""
        self._ids += 1
        message: dict[str, Any] = {"id": self._ids, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        data = json.dumps(message).encode() + b"\0"
        while data:
            data = data[os.write(self._w, data) :]
        deadline = time.monotonic() + 30
        while True:
            answer = self._receive(deadline)
            if answer.get("id") == self._ids:
                if "error" in answer:
                    raise RuntimeError(f"{method}: {answer['error']}")
                return answer.get("result", {})
            self.events.append(answer)

    def wait_for(self, method: str, session: str, timeout: float = 30) -> dict[str, Any]:
        """The first event ``method`` of ``session`` (already received or to come)."""
        deadline = time.monotonic() + timeout
        while True:
            for event in self.events:
                if event.get("method") == method and event.get("sessionId") == session:
                    return event
            self.events.append(self._receive(deadline))

    def open(self, url: str, width: int = 1280, height: int = 800) -> Tab:
        """A new tab that has loaded ``url``, with everything it logged watched from the start."""
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            self.call(f"{domain}.enable", session=session)
        self.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
            session,
        )
        navigated = self.call("Page.navigate", {"url": url}, session)
        tab = Tab(self, target, session)
        if navigated.get("errorText"):
            tab.navigation_error = navigated["errorText"]
        else:
            self.wait_for("Page.loadEventFired", session)
        return tab

    def close(self) -> None:
        with contextlib.suppress(OSError, RuntimeError, TimeoutError):
            self.call("Browser.close")
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)  # the browser this test started, and its helpers
            self.proc.wait(timeout=10)
        os.close(self._w)
        os.close(self._r)


class Tab:
    """One loaded page: its problems, its DOM through JavaScript, its picture."""

    def __init__(self, browser: Chromium, target: str, session: str) -> None:
        self.browser, self.target, self.session = browser, target, session
        self.navigation_error: str | None = None

    def evaluate(self, expression: str) -> Any:
        result = self.browser.call("Runtime.evaluate", {"expression": expression, "returnByValue": True}, self.session)
        assert "exceptionDetails" not in result, result["exceptionDetails"]
        return result["result"].get("value")

    def problems(self) -> list[str]:
        """Console errors, uncaught exceptions, failed requests and requests that leave the machine's
        files (anything but file: and data: URLs), as seen by the browser since the tab opened."""
        self.evaluate("1")  # a round trip: the events sent before it are in
        found = [f"navigation failed: {self.navigation_error}"] if self.navigation_error else []
        urls: dict[str, str] = {}
        for event in self.browser.events:
            if event.get("sessionId") != self.session:
                continue
            method, params = event.get("method"), event.get("params", {})
            if method == "Runtime.exceptionThrown":
                details = params["exceptionDetails"]
                found.append(f"exception: {details.get('exception', {}).get('description') or details.get('text')}")
            elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                found.append(
                    "console.error: " + " ".join(str(a.get("value", a.get("description"))) for a in params["args"])
                )
            elif method == "Log.entryAdded" and params["entry"].get("level") == "error":
                found.append(f"log: {params['entry'].get('text')} {params['entry'].get('url', '')}".strip())
            elif method == "Network.requestWillBeSent":
                url = params["request"]["url"]
                urls[params["requestId"]] = url
                if urlparse(url).scheme not in ("file", "data"):
                    found.append(f"request off the machine's files: {url}")
            elif method == "Network.loadingFailed":
                found.append(f"request failed: {urls.get(params['requestId'], '?')} {params.get('errorText')}")
        return found

    def screenshot(self, path: Path, max_height: int = 6000) -> Path:
        """A PNG of the whole page (up to ``max_height`` px) at 1280 px wide."""
        size = self.browser.call("Page.getLayoutMetrics", session=self.session)["cssContentSize"]
        clip = {"x": 0, "y": 0, "width": 1280, "height": min(size["height"], max_height), "scale": 1}
        shot = self.browser.call(
            "Page.captureScreenshot",
            {"format": "png", "captureBeyondViewport": True, "clip": clip},
            self.session,
        )
        path.write_bytes(base64.b64decode(shot["data"]))
        return path

    def close(self) -> None:
        self.browser.call("Target.closeTarget", {"targetId": self.target})
