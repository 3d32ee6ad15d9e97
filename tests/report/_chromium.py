"""Headless Debian chromium helpers shared by the report and study browser tests.

Loaded by file path (the test folders are not packages). ``inspect_page`` loads a page
through the DevTools protocol and returns the decoded state of its images and every
console error or exception.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import time
import urllib.request
from pathlib import Path

ARTIFACTS = Path(__file__).resolve().parents[1] / "artifacts"
FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-dev-shm-usage",
]


def find_chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def run_cmd(cmd, timeout=90):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)


def _devtools_port(user_dir: Path, proc: subprocess.Popen, timeout: float = 30.0) -> int:
    marker = user_dir / "DevToolsActivePort"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if marker.is_file() and marker.read_text().strip():
            return int(marker.read_text().split()[0])
        if proc.poll() is not None:
            raise RuntimeError(f"chromium exited early with code {proc.returncode}")
        time.sleep(0.1)
    raise RuntimeError("chromium did not open a DevTools port")


class _Cdp:
    """A minimal Chrome DevTools Protocol client over one page websocket."""

    def __init__(self, ws_url: str):
        import websocket

        self.ws = websocket.create_connection(ws_url, timeout=30, suppress_origin=True)
        self.next_id = 0
        self.events: list[dict] = []

    def call(self, method: str, **params):
        self.next_id += 1
        my_id = self.next_id
        self.ws.send(json.dumps({"id": my_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == my_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            self.events.append(msg)

    def wait_event(self, method: str, timeout: float = 30.0) -> dict:
        deadline = time.monotonic() + timeout
        for ev in self.events:
            if ev.get("method") == method:
                return ev
        while time.monotonic() < deadline:
            msg = json.loads(self.ws.recv())
            self.events.append(msg)
            if msg.get("method") == method:
                return msg
        raise TimeoutError(method)


def inspect_page(chromium: str, page_path: Path, user_dir: Path):
    """Load the page through DevTools; return (images [complete, naturalWidth], errors)."""
    proc = subprocess.Popen(
        [chromium, *FLAGS, f"--user-data-dir={user_dir}", "--remote-debugging-port=0",
         "about:blank"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    try:
        port = _devtools_port(user_dir, proc)
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as r:
            targets = json.load(r)
        page = next(t for t in targets if t.get("type") == "page")
        cdp = _Cdp(page["webSocketDebuggerUrl"])
        for domain in ("Runtime", "Log", "Page"):
            cdp.call(f"{domain}.enable")
        cdp.call("Page.navigate", url=page_path.as_uri())
        cdp.wait_event("Page.loadEventFired")
        res = cdp.call(
            "Runtime.evaluate", returnByValue=True,
            expression="Array.from(document.images).map(i => [i.complete, i.naturalWidth])",
        )
        images = res["result"]["value"]
        errors = [
            ev for ev in cdp.events
            if ev.get("method") == "Runtime.exceptionThrown"
            or (ev.get("method") == "Runtime.consoleAPICalled"
                and ev["params"].get("type") in ("error", "assert"))
            or (ev.get("method") == "Log.entryAdded"
                and ev["params"]["entry"].get("level") == "error")
        ]
        cdp.ws.close()
        return images, errors
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()


