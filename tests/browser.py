"""One headless Chromium per test process, driven over the DevTools protocol on a pipe.

Starting Chromium and compiling the WebGL shaders of a Plotly 3-D page in software
(SwiftShader) costs several CPU seconds per browser, in processes that a timer of the
test cannot see: 6-8 s of machine CPU per page when each page had a browser of its own.
One browser kept for the process renders each further page for less. Every page opens
in a tab of its own, with the same offline flags (no host name resolves) and a virtual
time budget, as ``chromium --virtual-time-budget`` gives a single page.

The protocol travels over ``--remote-debugging-pipe`` (file descriptors 3 and 4, JSON
messages ending in NUL), so no port is opened and no client library is needed.
"""

from __future__ import annotations

import atexit
import base64
import contextlib
import json
import os
import select
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

OFFLINE_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--hide-scrollbars",
    "--host-resolver-rules=MAP * ~NOTFOUND",  # no host name resolves: nothing can leave the machine
    "--disable-background-networking",
    "--no-first-run",
    "--disable-extensions",
]


class ChromiumPipe:
    """A headless Chromium and its DevTools connection (commands wait for their answer)."""

    def __init__(self, executable: str, timeout: float = 120.0):
        self.timeout = timeout
        self.profile = tempfile.mkdtemp(prefix="spacearm-chromium-")
        self.log = open(os.path.join(self.profile, "stderr.txt"), "w+b")  # noqa: SIM115 (closed in close())
        to_browser, from_browser = os.pipe(), os.pipe()
        child_ends = (to_browser[0], from_browser[1])
        # The browser reads commands on fd 3 and writes answers on fd 4: bash wires them (dash
        # takes one-digit descriptors only) and execs Chromium, so no Python code runs in the
        # child between fork and exec.
        wiring = f'exec "$@" 3<&{child_ends[0]} 4>&{child_ends[1]}'
        self.process = subprocess.Popen(
            [
                shutil.which("bash") or "/bin/bash",
                "-c",
                wiring,
                "bash",
                executable,
                *OFFLINE_FLAGS,
                "--remote-debugging-pipe",
            ]
            + [f"--user-data-dir={self.profile}", "about:blank"],
            pass_fds=child_ends,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=self.log,
            env={**os.environ, "HOME": self.profile},
        )
        os.close(child_ends[0])
        os.close(child_ends[1])
        self._write, self._read = to_browser[1], from_browser[0]
        self._buffer = b""
        self._next_id = 0
        self._events: list[dict] = []

    def alive(self) -> bool:
        return self.process.poll() is None

    def _message(self, deadline: float) -> dict:
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._read], [], [], left)[0]:
                raise TimeoutError(f"chromium did not answer in {self.timeout:g} s: {self.stderr_tail()}")
            chunk = os.read(self._read, 1 << 20)
            if not chunk:
                raise EOFError(f"chromium closed the DevTools pipe: {self.stderr_tail()}")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        """Send one command and return its result (events that arrive meanwhile are kept)."""
        self._next_id += 1
        command = {"id": self._next_id, "method": method, "params": params or {}}
        if session:
            command["sessionId"] = session
        os.write(self._write, json.dumps(command).encode() + b"\0")
        deadline = time.monotonic() + self.timeout
        while True:
            message = self._message(deadline)
            if message.get("id") == self._next_id:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})
            self._events.append(message)

    def wait_for(self, method: str, session: str) -> dict:
        """The next event ``method`` of the tab ``session``."""
        deadline = time.monotonic() + self.timeout
        while True:
            for i, event in enumerate(self._events):
                if event.get("method") == method and event.get("sessionId") == session:
                    return self._events.pop(i)
            self._events.append(self._message(deadline))

    def events(self, method: str, session: str) -> list[dict]:
        """Every kept event ``method`` of the tab ``session`` (removed from the queue)."""
        matched = [e for e in self._events if e.get("method") == method and e.get("sessionId") == session]
        self._events = [e for e in self._events if e not in matched]
        return matched

    def open(self, url: str, width: int, height: int, budget_ms: int) -> tuple[str, str]:
        """A new tab of ``width`` x ``height`` CSS pixels showing ``url`` once the page has had
        ``budget_ms`` of virtual time; returns (target, session)."""
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        self.send("Network.enable", session=session)
        self.send("Page.enable", session=session)
        self.send(
            "Emulation.setDeviceMetricsOverride",
            {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
            session=session,
        )
        self.send("Emulation.setVirtualTimePolicy", {"policy": "pause"}, session=session)
        self.send("Page.navigate", {"url": url}, session=session)
        self.send(
            "Emulation.setVirtualTimePolicy",
            {"policy": "pauseIfNetworkFetchesPending", "budget": budget_ms},
            session=session,
        )
        self.wait_for("Emulation.virtualTimeBudgetExpired", session)
        return target, session

    def close_tab(self, target: str, session: str) -> None:
        self.send("Target.closeTarget", {"targetId": target})
        self._events = [e for e in self._events if e.get("sessionId") != session]

    def stderr_tail(self) -> str:
        self.log.flush()
        self.log.seek(0)
        return self.log.read().decode(errors="replace")[-2000:]

    def close(self) -> None:
        if self.alive():
            try:
                self.send("Browser.close")
                self.process.wait(10)
            except (OSError, RuntimeError, TimeoutError, EOFError, subprocess.TimeoutExpired):
                self.process.kill()
                self.process.wait()
        for fd in (self._write, self._read):
            with contextlib.suppress(OSError):
                os.close(fd)
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)


_browser: ChromiumPipe | None = None


def browser(executable: str) -> ChromiumPipe:
    """The process's browser, started on first use (again if it died) and closed at exit."""
    global _browser
    if _browser is None or not _browser.alive():
        if _browser is not None:
            _browser.close()
        _browser = ChromiumPipe(executable)
        atexit.register(_browser.close)
    return _browser


def screenshot(executable: str, page: Path, out: Path, width: int = 1000, height: int = 700) -> list[str]:
    """Write ``page``'s screenshot to ``out`` (PNG) after 8 s of virtual time; return every URL
    the page requested (its own file included)."""
    chromium = browser(executable)
    target, session = chromium.open(Path(page).resolve().as_uri(), width, height, budget_ms=8000)
    try:
        shot = chromium.send("Page.captureScreenshot", {"format": "png"}, session=session)["data"]
        Path(out).write_bytes(base64.b64decode(shot))
        return [e["params"]["request"]["url"] for e in chromium.events("Network.requestWillBeSent", session)]
    finally:
        chromium.close_tab(target, session)


def body_data(executable: str, page: Path, width: int = 800, height: int = 600) -> dict[str, str]:
    """The ``data-*`` attributes on ``page``'s <body> after 8 s of virtual time."""
    chromium = browser(executable)
    target, session = chromium.open(Path(page).resolve().as_uri(), width, height, budget_ms=8000)
    try:
        result = chromium.send(
            "Runtime.evaluate",
            {"expression": "JSON.stringify(Object.assign({}, document.body.dataset))", "returnByValue": True},
            session=session,
        )["result"]
        return json.loads(result["value"])
    finally:
        chromium.close_tab(target, session)
