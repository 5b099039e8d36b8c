"""One headless Chromium per test process, driven over the DevTools protocol on a pipe.

Starting Chromium and compiling the WebGL shaders of a Plotly 3-D page in software
(SwiftShader) costs several CPU seconds per browser, in processes that a timer of the
test cannot see: 6-8 s of machine CPU per page when each page had a browser of its own.
One browser kept for the process renders each further page for less. Every page opens
in a tab of its own with the offline flags (no host name resolves) and the virtual time
budget that ``chromium --virtual-time-budget`` gives a single page (with the same
starvation count, so a page that keeps posting tasks still moves on). Unlike that
command, the budget starts at navigation and the viewport is exactly the size asked for.

The requests a page makes are collected from the tab and from every target it starts
(workers, iframes in other processes, attached automatically and paused until their
network events are on), WebSockets included: what Chromium's net log of a page showed.

The protocol travels over ``--remote-debugging-pipe`` (file descriptors 3 and 4, JSON
messages ending in NUL), so no port is opened and no client library is needed.
"""

from __future__ import annotations

import atexit
import base64
import contextlib
import glob
import json
import os
import re
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
    # Sandboxed and cross-site iframes in the page's own process, where its network events are.
    "--disable-site-isolation-trials",
    "--disable-features=IsolateSandboxedIframes,site-per-process",
]

# Network events and automatic attaching, for a tab and for each target it starts (which
# starts paused, ``waitForDebuggerOnStart``, until these are on).
_WATCH = (
    ("Network.enable", None),
    ("Target.setAutoAttach", {"autoAttach": True, "waitForDebuggerOnStart": True, "flatten": True}),
)
_PROFILE_PREFIX = "spacearm-chromium-"
_BROKEN = (TimeoutError, EOFError, OSError)  # the browser is gone or stuck: start a new one


class ChromiumPipe:
    """A headless Chromium and its DevTools connection (commands wait for their answer)."""

    def __init__(self, executable: str, timeout: float = 120.0):
        self.timeout = timeout
        _remove_stale_profiles()
        self.profile = tempfile.mkdtemp(prefix=f"{_PROFILE_PREFIX}{os.getpid()}-")
        self.log = open(os.path.join(self.profile, "stderr.txt"), "w+b")  # noqa: SIM115 (closed in close())
        to_browser, from_browser = os.pipe(), os.pipe()
        child_ends = (to_browser[0], from_browser[1])
        # The browser reads commands on fd 3 and writes answers on fd 4: bash wires them (dash
        # takes one-digit descriptors only) and execs Chromium, so no Python code runs in the
        # child between fork and exec.
        wiring = f'exec "$@" 3<&{child_ends[0]} 4>&{child_ends[1]}'
        self.process = subprocess.Popen(
            [shutil.which("bash") or "/bin/bash", "-c", wiring, "bash", executable, *OFFLINE_FLAGS]
            + ["--remote-debugging-pipe", f"--user-data-dir={self.profile}", "about:blank"],
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
        self._tab_of: dict[str, str] = {}  # session -> the tab session it belongs to (itself for a tab)
        self._attached: list[dict] = []  # targets a tab started, waiting for their network events

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

    def _keep(self, message: dict) -> None:
        """Keep an event of a tab (or of a target a tab started); drop the rest."""
        tab = self._tab_of.get(message.get("sessionId", ""))
        if tab is None:
            return  # the browser's own events, or a closed tab's
        if message.get("method") == "Target.attachedToTarget":
            self._tab_of[message["params"]["sessionId"]] = tab
            self._attached.append(message)
        elif message.get("method") == "Inspector.targetCrashed":
            raise RuntimeError(f"chromium's renderer crashed: {self.stderr_tail()}")
        self._events.append(message)

    def send(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        """Send one command and return its result (events that arrive meanwhile are kept)."""
        self._next_id += 1
        command = {"id": self._next_id, "method": method, "params": params or {}}
        if session:
            command["sessionId"] = session
        try:
            os.write(self._write, json.dumps(command).encode() + b"\0")
        except OSError as error:
            raise EOFError(f"chromium is gone ({error}): {self.stderr_tail()}") from error
        deadline = time.monotonic() + self.timeout
        while True:
            message = self._message(deadline)
            if message.get("id") == self._next_id:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})
            self._keep(message)

    def _release_attached(self) -> None:
        """Watch each target a tab started (`_WATCH`), then let it run."""
        while self._attached:
            session = self._attached.pop(0)["params"]["sessionId"]
            # Each step on its own: a worker has no Target domain, and a target may have ended.
            for method, params in (*_WATCH, ("Runtime.runIfWaitingForDebugger", None)):
                with contextlib.suppress(RuntimeError):
                    self.send(method, params, session=session)

    def wait_for(self, method: str, session: str) -> dict:
        """The next event ``method`` of the tab ``session`` (releasing the targets it starts meanwhile)."""
        deadline = time.monotonic() + self.timeout
        while True:
            self._release_attached()
            for i, event in enumerate(self._events):
                if event.get("method") == method and event.get("sessionId") == session:
                    return self._events.pop(i)
            self._keep(self._message(deadline))

    def requested(self, tab: str) -> list[str]:
        """Every URL the tab and the targets it started requested, WebSockets included."""
        urls = []
        for event in self._events:
            if self._tab_of.get(event.get("sessionId", "")) != tab:
                continue
            if event.get("method") == "Network.requestWillBeSent":
                urls.append(event["params"]["request"]["url"])
            elif event.get("method") == "Network.webSocketCreated":
                urls.append(event["params"]["url"])
        return urls

    def open(self, url: str, width: int, height: int, budget_ms: int) -> tuple[str, str]:
        """A new tab of ``width`` x ``height`` CSS pixels showing ``url`` once the page has had
        ``budget_ms`` of virtual time; returns (target, session)."""
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = None
        try:
            session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
            self._tab_of[session] = session
            for method, params in _WATCH:
                self.send(method, params, session=session)
            self.send("Page.enable", session=session)
            self.send(
                "Emulation.setDeviceMetricsOverride",
                {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
                session=session,
            )
            self.send("Emulation.setVirtualTimePolicy", {"policy": "pause"}, session=session)
            navigated = self.send("Page.navigate", {"url": url}, session=session)
            if navigated.get("errorText"):
                raise RuntimeError(f"chromium could not open {url}: {navigated['errorText']}")
            budget = {"policy": "pauseIfNetworkFetchesPending", "budget": budget_ms}
            budget["maxVirtualTimeTaskStarvationCount"] = 9999  # as --virtual-time-budget sets it
            self.send("Emulation.setVirtualTimePolicy", budget, session=session)
            self.wait_for("Emulation.virtualTimeBudgetExpired", session)
        except _BROKEN:
            raise  # the caller drops the browser
        except BaseException:
            self.close_tab(target, session)
            raise
        return target, session

    def close_tab(self, target: str, session: str | None) -> None:
        with contextlib.suppress(*_BROKEN, RuntimeError):
            self.send("Target.closeTarget", {"targetId": target})
        if session is not None:
            closed = {s for s, tab in self._tab_of.items() if tab == session}
            self._tab_of = {s: tab for s, tab in self._tab_of.items() if s not in closed}
            self._events = [e for e in self._events if e.get("sessionId") not in closed]

    def stderr_tail(self) -> str:
        if self.log.closed:
            return ""
        self.log.flush()
        self.log.seek(0)
        return self.log.read().decode(errors="replace")[-2000:]

    def close(self) -> None:
        """Close the browser (once; later calls do nothing) and remove its profile."""
        if self._write < 0:
            return
        if self.alive():
            self.timeout = 5.0
            try:
                self.send("Browser.close")
                self.process.wait(5)
            except (*_BROKEN, RuntimeError, subprocess.TimeoutExpired):
                self.process.kill()
                self.process.wait()
        for fd in (self._write, self._read):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._write = self._read = -1
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)


def _remove_stale_profiles() -> None:
    """Profiles of browsers whose test process ended without closing them (``os._exit``)."""
    for folder in glob.glob(os.path.join(tempfile.gettempdir(), f"{_PROFILE_PREFIX}*")):
        match = re.match(rf"{_PROFILE_PREFIX}(\d+)-", os.path.basename(folder))
        if match and not _running(int(match.group(1))):
            shutil.rmtree(folder, ignore_errors=True)


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


_browser: ChromiumPipe | None = None


def _close_browser() -> None:
    if _browser is not None:
        _browser.close()


atexit.register(_close_browser)


def browser(executable: str) -> ChromiumPipe:
    """The process's browser, started on first use (again if it died) and closed at exit."""
    global _browser
    if _browser is None or not _browser.alive():
        _close_browser()
        _browser = ChromiumPipe(executable)
    return _browser


@contextlib.contextmanager
def _tab(executable: str, page: Path, width: int, height: int):
    """A tab showing ``page`` after 8 s of virtual time; a browser that times out or dies is
    dropped (the next page starts a new one)."""
    global _browser
    chromium = browser(executable)
    target = session = None
    try:
        target, session = chromium.open(Path(page).resolve().as_uri(), width, height, budget_ms=8000)
        yield chromium, session
    except _BROKEN:
        chromium.close()
        _browser = None
        raise
    finally:
        if _browser is chromium and target is not None:  # (open closes its own tab when it fails)
            chromium.close_tab(target, session)


def screenshot(executable: str, page: Path, out: Path, width: int = 1000, height: int = 700) -> list[str]:
    """Write ``page``'s screenshot to ``out`` (PNG) after 8 s of virtual time; return every URL
    the page (and any worker or iframe it started) requested, its own file included."""
    with _tab(executable, page, width, height) as (chromium, session):
        shot = chromium.send("Page.captureScreenshot", {"format": "png"}, session=session)["data"]
        Path(out).write_bytes(base64.b64decode(shot))
        return chromium.requested(session)


def body_data(executable: str, page: Path, width: int = 800, height: int = 600) -> dict[str, str]:
    """The ``data-*`` attributes on ``page``'s <body> after 8 s of virtual time."""
    with _tab(executable, page, width, height) as (chromium, session):
        evaluated = chromium.send(
            "Runtime.evaluate",
            {"expression": "JSON.stringify(Object.assign({}, document.body.dataset))", "returnByValue": True},
            session=session,
        )
        if "exceptionDetails" in evaluated:
            raise RuntimeError(f"reading <body> of {page}: {evaluated['exceptionDetails']}")
        return json.loads(evaluated["result"]["value"])
